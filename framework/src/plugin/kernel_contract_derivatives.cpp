// The kernel contract's derivative checks (d = 1) and gradient check (d > 1), declared in
// contract_checks.hpp; the other checks are kernel_contract.cpp.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "contract_checks.hpp"
#include "rkhs/core/random.hpp"
#include "rkhs/kernel/kernel_algorithms.hpp"

namespace rkhs::contract_detail {

namespace {

// Distance from s to the nearest of the sorted points `kinks` (periodic distance on a periodic
// domain); infinity when there are none.
double distance_to_nearest(const Domain& domain, const std::vector<double>& kinks, double s) {
  double nearest = std::numeric_limits<double>::infinity();
  if (kinks.empty()) return nearest;
  const double x = domain.wrap(s);
  const auto next = std::lower_bound(kinks.begin(), kinks.end(), x);
  if (next != kinks.end()) nearest = std::min(nearest, domain.distance(x, *next));
  if (next != kinks.begin()) nearest = std::min(nearest, domain.distance(x, *(next - 1)));
  if (domain.periodic) {
    nearest = std::min(nearest, domain.distance(x, kinks.front()));
    nearest = std::min(nearest, domain.distance(x, kinks.back()));
  }
  return nearest;
}

}  // namespace

// The derivative checks (header): derivative() against Richardson extrapolation, and a basis'
// derivatives against derivative().
void check_derivatives(const AnyKernel& kernel, double scale, Checks& checks) {
  const Domain& domain = kernel.domain();
  const double length = domain.length;
  const double radius = kernel.properties().support_radius;
  auto kinks = kernel.kink_points();
  std::sort(kinks.begin(), kinks.end());
  const auto centres = golden_ratio_points(7, length, 0.42);
  const auto points = golden_ratio_points(29, length, 0.17);

  // Where k(c, .) may not be smooth: the kernel's kink points, s = c, |s - c| = radius (a
  // stationary kernel's profile may have kinks there), and an interval's ends. The reference
  // needs a smooth stretch around s; pairs closer than 1e-6 L to one are left out.
  struct Pair {
    double centre, point, derivative, reference;
  };
  std::vector<Pair> pairs;
  int left_out = 0;
  double largest_slope = 0;
  for (double c : centres) {
    for (double s : points) {
      double gap = std::min(distance_to_nearest(domain, kinks, s), domain.distance(s, c));
      if (radius > 0)
        gap = std::min({gap, domain.distance(s, c + radius), domain.distance(s, c - radius)});
      if (!domain.periodic) gap = std::min({gap, s, length - s});
      if (gap < 1e-6 * length) {
        ++left_out;
        continue;
      }
      double error = 0;
      const double reference =
          richardson_derivative([&](double t) { return kernel.evaluate(c, t); }, s,
                                std::min(0.5 * gap, 0.05 * length), error);
      pairs.push_back({c, s, kernel.derivative(c, s), reference});
      largest_slope = std::max(largest_slope, std::abs(reference));
    }
  }
  // A slope scale with the units of dk/ds, nonzero for a kernel whose sections are flat.
  const double slope_scale = std::max(largest_slope, scale / length);
  double worst = 0;
  std::string worst_at = "";
  for (const auto& pair : pairs) {
    const double deviation = std::abs(pair.derivative - pair.reference) / slope_scale;
    if (!(deviation <= worst)) {  // NaN too
      worst = std::isnan(deviation) ? std::numeric_limits<double>::infinity() : deviation;
      worst_at = fmt::format(" at c = {}, s = {}: {} against {}", g(pair.centre), g(pair.point),
                             g(pair.derivative), g(pair.reference));
    }
  }
  if (pairs.empty()) {
    checks.skip("derivative", "every sample point is within 1e-6 L of a possible kink");
  } else {
    checks.at_most(
        "derivative",
        fmt::format("{} ({}) at {} pairs (c, s), max |dk/ds - Richardson| / "
                    "max(max |dk/ds|, max k / L){}",
                    kernel.has_exact_derivative() ? "closed form" : "difference quotient",
                    kernel.name(), pairs.size(), worst_at),
        worst, 1e-6);
  }

  // A basis' derivatives: evaluate_derivative against derivative(c_i, s), at scattered points
  // and at the centres themselves; evaluate_mapped_derivative against T dphi(s).
  const auto basis_centres = golden_ratio_points(12, length, 0.63);
  const auto basis = kernel.basis(basis_centres);
  Random random(hash64(kernel.name() + " derivative"));
  Eigen::MatrixXd map(5, 12);
  for (Eigen::Index i = 0; i < map.rows(); ++i)
    for (Eigen::Index j = 0; j < map.cols(); ++j) map(i, j) = 2 * random.uniform() - 1;
  basis->set_map(map);
  const double map_norm = map.cwiseAbs().rowwise().sum().maxCoeff();
  Eigen::VectorXd dphi(12), mapped(5);
  double basis_error = 0, mapped_error = 0;
  auto compare_at = [&](double s) {
    basis->evaluate_derivative(s, dphi.data());
    for (Eigen::Index i = 0; i < 12; ++i)
      basis_error = std::max(
          basis_error, std::abs(dphi(i) - kernel.derivative(basis_centres[i], s)) / slope_scale);
    basis->evaluate_mapped_derivative(s, mapped.data());
    mapped_error = std::max(mapped_error,
                            (mapped - map * dphi).cwiseAbs().maxCoeff() / (slope_scale * map_norm));
    if (std::isnan(dphi.sum() + mapped.sum()))
      basis_error = std::numeric_limits<double>::infinity();
  };
  for (double s : points) compare_at(s);
  for (double c : basis_centres) compare_at(c);
  // Closed forms: the same products summed in another order, ~n eps. Difference quotients of a
  // feature basis difference Phi_c f(s) (or T Phi_c f(s)), rounded unlike k(c, s): the quotient
  // amplifies that rounding by 1 / h, so up to ~16 eps max k / h more.
  const double step = DerivativeStencil::relative_step * length;
  const double tolerance =
      1e-12 + (kernel.has_exact_derivative() ? 0.0 : 16 * epsilon * scale / (step * slope_scale));
  checks.at_most("basis derivative",
                 "max |evaluate_derivative - derivative(c_i, s)|, |evaluate_mapped_derivative - "
                 "T dphi| / slope scale, at 29 points and the 12 centres",
                 std::max(basis_error, mapped_error), tolerance);
}

// The gradient check (d > 1): each component of gradient_point(c, y) against Richardson
// extrapolation of k(c, .) along that axis, where the section is smooth along the stretch.
void check_gradient(const AnyKernel& kernel, double scale, Checks& checks,
                    const std::function<std::vector<double>(std::size_t, double)>& scatter) {
  const Domain& domain = kernel.domain();
  const auto d = static_cast<std::size_t>(domain.dimension);
  const double radius = kernel.properties().support_radius;
  auto kinks = kernel.kink_points();  // along axis 0; axis a has them scaled by L_a / L
  std::sort(kinks.begin(), kinks.end());
  const auto centres = scatter(5, 0.42), points = scatter(19, 0.17);
  double largest_slope = 0, worst = 0;
  std::string worst_at;
  struct Component {
    std::size_t centre, point, axis;
    double gradient, reference;
  };
  std::vector<Component> components;
  std::vector<double> c(d), y(d), gradient(d), moved(d);
  int left_out = 0;
  for (std::size_t i = 0; i < centres.size() / d; ++i)
    for (std::size_t m = 0; m < points.size() / d; ++m) {
      std::copy_n(centres.begin() + static_cast<std::ptrdiff_t>(i * d), d, c.begin());
      std::copy_n(points.begin() + static_cast<std::ptrdiff_t>(m * d), d, y.begin());
      kernel.gradient_point(c, y, gradient);
      double distance2 = 0;
      for (std::size_t a = 0; a < d; ++a) {
        const double t = domain.difference(c[a], y[a], static_cast<int>(a));
        distance2 += t * t;
      }
      const double distance = std::sqrt(distance2);
      for (std::size_t a = 0; a < d; ++a) {
        const auto axis = static_cast<int>(a);
        const double extent = domain.extent(axis);
        // Smooth along axis a near y: away from the centre, the support's sphere, the axis'
        // kinks and (on a box) its faces.
        double gap = distance;
        if (radius > 0) gap = std::min(gap, std::abs(distance - radius));
        for (double kink : kinks) {
          const double position = kink * extent / domain.length;
          gap = std::min(gap, std::abs(domain.difference(position, y[a], axis)));
        }
        if (!domain.periodic) gap = std::min({gap, y[a], extent - y[a]});
        if (gap < 1e-6 * extent) {
          ++left_out;
          continue;
        }
        double error = 0;
        const double reference = richardson_derivative(
            [&](double t) {
              moved = y;
              moved[a] = t;
              return kernel.evaluate_point(c, moved);
            },
            y[a], std::min(0.5 * gap, 0.05 * extent), error);
        components.push_back({i, m, a, gradient[a], reference});
        largest_slope = std::max(largest_slope, std::abs(reference));
      }
    }
  const double slope_scale = std::max(largest_slope, scale / domain.length);
  for (const auto& component : components) {
    const double deviation = std::abs(component.gradient - component.reference) / slope_scale;
    if (!(deviation <= worst)) {
      worst = std::isnan(deviation) ? std::numeric_limits<double>::infinity() : deviation;
      worst_at = fmt::format(" at centre {}, point {}, axis {}: {} against {}", component.centre,
                             component.point, component.axis + 1, g(component.gradient),
                             g(component.reference));
    }
  }
  if (components.empty()) {
    checks.skip("gradient", "every sample point is within 1e-6 L of a possible kink");
    return;
  }
  checks.at_most("gradient",
                 fmt::format("{} ({}) at {} components (centre, point, axis), max |dk/dy_a - "
                             "Richardson| / max(max |dk/dy_a|, max k / L){}",
                             kernel.has_exact_gradient() ? "closed form" : "difference quotient",
                             kernel.name(), components.size(), worst_at),
                 worst, 1e-6);
}


}  // namespace rkhs::contract_detail
