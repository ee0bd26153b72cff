#include "rkhs/plugin/kernel_contract.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "contract_checks.hpp"
#include "rkhs/core/random.hpp"
#include "rkhs/kernel/kernel_algorithms.hpp"

namespace rkhs {

using namespace contract_detail;

double richardson_derivative(const std::function<double(double)>& f, double s, double largest_step,
                             double& error) {
  // Ridders' method (Numerical Recipes, 3rd ed., section 5.7): each row shrinks h by 1.4, each
  // column eliminates one more even power of h; a run stops when the diagonal's change exceeds
  // twice its best error estimate (higher order is no longer paying). Several starting steps
  // cover kernels whose width is far below the largest step the stretch allows.
  constexpr int rows = 12;
  constexpr double shrink = 1.4, shrink2 = shrink * shrink, safe = 2.0;
  double best = std::numeric_limits<double>::quiet_NaN();
  error = std::numeric_limits<double>::infinity();
  auto central = [&](double h) {
    const double ahead = s + h, behind = s - h;
    return (f(ahead) - f(behind)) / (ahead - behind);
  };
  for (double start : {1.0, 1e-1, 1e-2, 1e-3}) {
    double table[rows][rows];
    double h = start * largest_step;
    double run_error = std::numeric_limits<double>::infinity();
    table[0][0] = central(h);
    for (int i = 1; i < rows; ++i) {
      h /= shrink;
      table[0][i] = central(h);
      double factor = shrink2;
      for (int j = 1; j <= i; ++j) {
        table[j][i] = (table[j - 1][i] * factor - table[j - 1][i - 1]) / (factor - 1);
        factor *= shrink2;
        const double estimate = std::max(std::abs(table[j][i] - table[j - 1][i]),
                                         std::abs(table[j][i] - table[j - 1][i - 1]));
        if (estimate <= run_error) {
          run_error = estimate;
          if (estimate <= error) {
            error = estimate;
            best = table[j][i];
          }
        }
      }
      if (std::abs(table[i][i] - table[i - 1][i - 1]) >= safe * run_error) break;
    }
  }
  return best;
}

bool ContractReport::passed() const noexcept {
  return std::all_of(checks.begin(), checks.end(), [](const auto& c) { return c.passed; });
}

std::vector<std::string> ContractReport::failures() const {
  std::vector<std::string> out;
  for (const auto& c : checks)
    if (!c.passed) out.push_back(c.name + ": " + c.detail);
  return out;
}

std::vector<double> golden_ratio_points(std::size_t count, double length, double start) {
  const double golden = 0.61803398874989484820;
  std::vector<double> out(count);
  double u = start;
  for (auto& s : out) {
    u += golden;
    u -= std::floor(u);
    s = u * length;
  }
  return out;
}

std::vector<double> nested_uniform_centres(std::size_t n, double length) {
  std::vector<double> out(n);
  for (std::size_t i = 0; i < n; ++i)
    out[i] = static_cast<double>(i) * length / static_cast<double>(n);
  return out;
}

PowerFunctionSquared power_function_squared(const AnyKernel& kernel,
                                            const std::vector<double>& centres,
                                            const std::vector<double>& points) {
  const Eigen::MatrixXd gram = kernel.gram(centres);
  const auto n = static_cast<double>(kernel.domain().point_count(centres));
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(gram);
  const Eigen::VectorXd& lambda = eigen.eigenvalues();
  const double lambda_max = lambda.maxCoeff();
  const double cutoff = 1e3 * n * epsilon * lambda_max;
  const Eigen::MatrixXd projections = kernel.cross(points, centres) * eigen.eigenvectors();
  const Eigen::VectorXd diagonal = kernel.diagonal(points);

  PowerFunctionSquared out;
  out.squared = diagonal;
  double lambda_min_kept = lambda_max;
  for (Eigen::Index i = 0; i < lambda.size(); ++i) {
    if (lambda(i) <= cutoff) {
      ++out.dropped;
      continue;
    }
    lambda_min_kept = std::min(lambda_min_kept, lambda(i));
    out.squared -= projections.col(i).cwiseAbs2() / lambda(i);
  }
  out.condition = lambda_max / lambda_min_kept;
  out.tolerance = 32 * n * epsilon * out.condition * diagonal.maxCoeff();
  return out;
}

std::vector<double> scattered_points(const Domain& domain, std::size_t count, double start) {
  if (domain.dimension == 1) return golden_ratio_points(count, domain.length, start);
  // The Kronecker sequence of the generalised golden ratio phi_d (x^(d+1) = x + 1):
  // u_p = frac(start + p / phi_d^a), a = 1..d; every prefix is spread out.
  const auto d = static_cast<std::size_t>(domain.dimension);
  double phi = 2.0;
  for (int i = 0; i < 64; ++i) phi = std::pow(1.0 + phi, 1.0 / static_cast<double>(d + 1));
  std::vector<double> out(count * d);
  for (std::size_t p = 0; p < count; ++p)
    for (std::size_t a = 0; a < d; ++a) {
      double u = start + static_cast<double>(p + 1) / std::pow(phi, static_cast<double>(a + 1));
      u -= std::floor(u);
      out[p * d + a] = u * domain.extent(static_cast<int>(a));
    }
  return out;
}

namespace {

// The declared properties, consistent with each other and with the domain.
void check_metadata(const AnyKernel& kernel, Checks& checks) {
  const auto props = kernel.properties();
  std::vector<std::string> metadata_problems;
  if (props.analytic && props.sobolev_order)
    metadata_problems.push_back("both analytic and a Sobolev order");
  const int d = kernel.domain().dimension;
  // H^tau in C(Omega) needs tau > d/2.
  if (props.sobolev_order && !(*props.sobolev_order > 0.5 * d))
    metadata_problems.push_back(
        fmt::format("Sobolev order {} <= d/2 = {}", g(*props.sobolev_order), g(0.5 * d)));
  if (!(props.support_radius >= 0)) metadata_problems.push_back("negative support radius");
  if (kernel.feature_count() > 0 && props.positive_definite)  // rank <= features
    metadata_problems.push_back("positive definite with a finite feature map");
  if (props.dimension != d)
    metadata_problems.push_back(fmt::format(
        "dimension {} on a domain of dimension {} (properties().dimension must be the domain's)",
        props.dimension, d));
  checks.add("metadata", metadata_problems.empty(),
             metadata_problems.empty() ? "consistent" : fmt::format("{}", fmt::join(metadata_problems, "; ")));
}

// A kernel on flat point sets: point(set, p) is point p of `set` (the domain's dimension
// coordinates each), k(x, y) the kernel at two such points.
struct FlatPoints {
  const AnyKernel& kernel;
  std::size_t dimension = static_cast<std::size_t>(kernel.domain().dimension);
  std::span<const double> point(const std::vector<double>& set, std::size_t p) const {
    return std::span<const double>(set).subspan(p * dimension, dimension);
  }
  double k(std::span<const double> x, std::span<const double> y) const {
    return kernel.evaluate_point(x, y);
  }
};

// Symmetry, periodicity, compact support, stationarity on pairs of `points` (scale: max k).
void check_pairs(const AnyKernel& kernel, const std::vector<double>& points, double scale,
                 Checks& checks) {
  const Domain& domain = kernel.domain();
  const std::size_t point_count = domain.point_count(points);
  const auto d_points = static_cast<std::size_t>(domain.dimension);
  const FlatPoints flat{kernel};
  const auto props = kernel.properties();

  // Symmetry, periodicity, compact support, stationarity on pairs of scattered points. In
  // d > 1 the periods are shifts along each axis, the stationarity shift is 0.3 of every extent.
  double asymmetry = 0, aperiodicity = 0, outside_support = 0, nonstationarity = 0;
  std::vector<double> moved_x(d_points), moved_y(d_points);
  for (std::size_t i = 0; i < point_count; ++i) {
    const auto x = flat.point(points, i);
    for (std::size_t j = 0; j < point_count; ++j) {
      const auto y = flat.point(points, j);
      const double kxy = flat.k(x, y);
      asymmetry = std::max(asymmetry, std::abs(kxy - flat.k(y, x)));
      if (domain.periodic) {
        for (std::size_t a = 0; a < d_points; ++a) {
          const double period = domain.extent(static_cast<int>(a));
          std::copy(x.begin(), x.end(), moved_x.begin());
          std::copy(y.begin(), y.end(), moved_y.begin());
          moved_x[a] += period;
          moved_y[a] -= 2 * period;
          aperiodicity = std::max(aperiodicity, std::abs(flat.k(moved_x, y) - kxy));
          aperiodicity = std::max(aperiodicity, std::abs(flat.k(x, moved_y) - kxy));
        }
      }
      if (props.support_radius > 0 &&
          std::sqrt(domain.squared_distance(x.data(), y.data())) >= props.support_radius)
        outside_support = std::max(outside_support, std::abs(kxy));
      if (props.stationary) {
        bool inside = true;
        for (std::size_t a = 0; a < d_points; ++a) {
          const double shift = 0.3 * domain.extent(static_cast<int>(a));
          moved_x[a] = x[a] + shift;
          moved_y[a] = y[a] + shift;
          inside = inside && moved_x[a] <= domain.extent(static_cast<int>(a)) &&
                   moved_y[a] <= domain.extent(static_cast<int>(a));
        }
        if (domain.periodic || inside)
          nonstationarity = std::max(nonstationarity, std::abs(flat.k(moved_x, moved_y) - kxy));
      }
    }
  }
  checks.at_most("symmetry", "max |k(x,y) - k(y,x)| / max k", asymmetry / scale, 1e-14);
  if (props.periodic != domain.periodic) {
    checks.add("periodicity", false,
               fmt::format("declared periodic = {} on {} domain", props.periodic ? "yes" : "no",
                           domain.periodic ? "a periodic" : "an interval"));
  } else if (domain.periodic) {
    // x + L rounds: |dk| <= |k'| eps L.
    checks.at_most("periodicity", "max |k(x+L,y) - k(x,y)|, |k(x,y-2L) - k(x,y)| / max k",
                   aperiodicity / scale, 1e-11);
  } else {
    checks.skip("periodicity", "interval domain, declared not periodic");
  }
  if (props.support_radius > 0)
    checks.at_most("compact support", "max |k(x,y)| at distance >= radius", outside_support, 0.0);
  else
    checks.skip("compact support", "global support declared");
  if (props.stationary)
    checks.at_most("stationarity", "max |k(x+t,y+t) - k(x,y)| / max k", nonstationarity / scale,
                   1e-11);
  else
    checks.skip("stationarity", "not declared stationary");
}

// Random point sets: no structure a kernel could accidentally be kind to.
void check_random_gram(const AnyKernel& kernel, Checks& checks) {
  const Domain& domain = kernel.domain();
  const auto d_points = static_cast<std::size_t>(domain.dimension);
  Random random(hash64(kernel.name()));
  double worst = 0;  // most negative lambda_min / allowed
  std::string where = "none negative";
  for (std::size_t count : {10u, 25u, 50u}) {
    for (int set = 0; set < 3; ++set) {
      std::vector<double> random_points(count * d_points);
      for (std::size_t c = 0; c < random_points.size(); ++c)
        random_points[c] = random.uniform() * domain.extent(static_cast<int>(c % d_points));
      const auto random_spectrum = spectrum_of(kernel.gram(random_points));
      const double ratio = -random_spectrum.lambda.minCoeff() / random_spectrum.allowed_negative;
      if (ratio > worst) {
        worst = ratio;
        where = fmt::format("lambda_min = {} at {} points (tolerance -{})",
                            g(random_spectrum.lambda.minCoeff()), count,
                            g(random_spectrum.allowed_negative));
      }
    }
  }
  checks.add("Gram positive semidefinite on random point sets", worst <= 1.0,
             fmt::format("9 sets of 10, 25, 50 points: {}", where));
}

// The Gram and cross matrices against evaluate() and diagonal(), the Gram matrix positive
// semidefinite and of at most the feature map's rank. False when a matrix has the wrong size
// (the checks stop there).
bool check_matrices(const AnyKernel& kernel, const std::vector<double>& points, double scale,
                    Checks& checks) {
  const Domain& domain = kernel.domain();
  const std::size_t point_count = domain.point_count(points);
  const FlatPoints flat{kernel};

  // Gram matrix: symmetric positive semidefinite, diagonal = diagonal(), entries = evaluate().
  const auto centres = scattered_points(domain, 40, 0.77);
  const Eigen::MatrixXd gram = kernel.gram(centres);
  if (gram.rows() != 40 || gram.cols() != 40) {
    checks.add("Gram matrix size", false,
               fmt::format("{} x {} for 40 centres", gram.rows(), gram.cols()));
    return false;
  }
  checks.at_most("Gram symmetric", "max |G - G^T|", (gram - gram.transpose()).cwiseAbs().maxCoeff(),
                 0.0);
  const auto spectrum = spectrum_of(gram);
  const Eigen::VectorXd& lambda = spectrum.lambda;
  checks.add("Gram positive semidefinite", lambda.minCoeff() >= -spectrum.allowed_negative,
             fmt::format("40 scattered points: eigenvalues {} .. {} (tolerance -{})",
                         g(lambda.minCoeff()), g(lambda.maxCoeff()), g(spectrum.allowed_negative)));
  check_random_gram(kernel, checks);
  checks.at_most("Gram diagonal", "max |G_ii - k(c_i, c_i)| / max k",
                 (gram.diagonal() - kernel.diagonal(centres)).cwiseAbs().maxCoeff() / scale, 1e-14);
  if (kernel.feature_count() > 0 && kernel.feature_count() < 40) {
    const auto rank_bound = static_cast<Eigen::Index>(kernel.feature_count());
    checks.at_most(
        "feature-map rank",
        fmt::format("eigenvalue {} of 40 ({} features) / lambda_max", 40 - rank_bound, rank_bound),
        lambda(39 - rank_bound) / lambda.maxCoeff(), 64 * 40 * epsilon);
  } else {
    checks.skip("feature-map rank", kernel.feature_count() ? "at least as many features as centres"
                                                           : "no finite feature map");
  }

  const Eigen::MatrixXd cross = kernel.cross(points, centres);
  if (cross.rows() != static_cast<Eigen::Index>(point_count) || cross.cols() != 40) {
    checks.add("cross matrix size", false, fmt::format("{} x {}", cross.rows(), cross.cols()));
    return false;
  }
  double cross_error = 0;
  for (Eigen::Index m = 0; m < cross.rows(); ++m)
    for (Eigen::Index i = 0; i < cross.cols(); ++i)
      cross_error = std::max(
          cross_error,
          std::abs(cross(m, i) - flat.k(flat.point(points, static_cast<std::size_t>(m)),
                                        flat.point(centres, static_cast<std::size_t>(i)))));
  checks.at_most("cross matrix", "max |K_mi - k(s_m, c_i)| / max k", cross_error / scale, 1e-14);
  return true;
}

// The power function on nested centres: >= 0, ~0 at the centres, non-increasing.
void check_power_function(const AnyKernel& kernel, double scale, Checks& checks,
                          ContractReport& report) {
  const Domain& domain = kernel.domain();
  const double length = domain.length;
  const auto d_points = static_cast<std::size_t>(domain.dimension);
  // Power function on nested centres 4 -> 8 -> 16 (uniform in d = 1, the first n scattered
  // points in d > 1): >= 0, ~0 at the centres, non-increasing as centres are added.
  auto evaluation = scattered_points(domain, 257, 0.31);
  const auto finest = domain.dimension == 1 ? nested_uniform_centres(16, length)
                                            : scattered_points(domain, 16, 0.59);
  evaluation.insert(evaluation.end(), finest.begin(), finest.end());
  // The centres of n among the 16: every (16/n)-th uniform one, or the first n scattered ones.
  auto nested_centres = [&](std::size_t n) {
    if (domain.dimension == 1) return nested_uniform_centres(n, length);
    return std::vector<double>(finest.begin(), finest.begin() + static_cast<long>(n * d_points));
  };
  auto is_centre_of = [&](std::size_t i, std::size_t n) {
    return domain.dimension == 1 ? i % (16 / n) == 0 : i < n;
  };
  PowerFunctionSquared previous;
  double worst_negative = 0, worst_at_centres = 0, worst_increase = 0;
  bool nonnegative = true, zero_at_centres = true, nonincreasing = true;
  std::string skipped_because;
  for (std::size_t n : {4u, 8u, 16u}) {
    const auto nested = nested_centres(n);
    const auto power = power_function_squared(kernel, nested, evaluation);
    const double negative = -power.squared.minCoeff();
    worst_negative = std::max(worst_negative, negative / std::max(power.tolerance, 1e-300));
    if (negative > power.tolerance) nonnegative = false;
    // Evaluation points 257 + 16j are the uniform centres of 16; every n-th of them is a centre.
    double at_centres = 0;
    for (std::size_t i = 0; i < 16; ++i)
      if (is_centre_of(i, n))
        at_centres =
            std::max(at_centres, std::abs(power.squared(static_cast<Eigen::Index>(257 + i))));
    worst_at_centres = std::max(worst_at_centres, at_centres / scale);
    if (at_centres > power.tolerance + 1e-14 * scale) zero_at_centres = false;
    if (n > 4) {
      // Truncating a nonzero (ill-conditioned) eigenvalue changes the space, so the nested
      // comparison is only meaningful without truncation, or for a finite feature map, whose
      // Gram matrices beyond its rank are exactly singular (the dropped eigenvalues are zeros),
      // and when the tolerance is small.
      const bool meaningful =
          (power.dropped == 0 && previous.dropped == 0) || kernel.feature_count() > 0;
      const double tolerance = power.tolerance + previous.tolerance;
      if (meaningful && tolerance < 1e-6 * scale) {
        const double increase = (power.squared - previous.squared).maxCoeff();
        worst_increase = std::max(worst_increase, increase / scale);
        if (increase > tolerance) nonincreasing = false;
        ++report.monotonicity_comparisons;
      } else {
        skipped_because = fmt::format("n = {}: condition {}, {} eigenvalues dropped", n,
                                      g(power.condition), power.dropped);
      }
    }
    previous = power;
  }
  checks.add("power function non-negative", nonnegative,
             fmt::format("n = 4, 8, 16: worst -min P^2 = {} x its round-off tolerance",
                         g(worst_negative)));
  checks.add("power function zero at centres", zero_at_centres,
             fmt::format("max P^2 at the centres / max k = {}", g(worst_at_centres)));
  if (report.monotonicity_comparisons > 0) {
    checks.add(
        "power function non-increasing", nonincreasing,
        fmt::format("largest increase of P^2 from n/2 to n / max k = {}{}", g(worst_increase),
                    skipped_because.empty() ? "" : " (some n skipped: " + skipped_because + ")"));
  } else {
    checks.skip("power function non-increasing",
                "round-off makes the nested comparison meaningless (" + skipped_because + ")");
  }
}

}  // namespace

ContractReport check_kernel_contract(const AnyKernel& kernel) {
  ContractReport report;
  Checks checks(report);
  const Domain& domain = kernel.domain();
  const auto points = scattered_points(domain, 61, 0.1234);
  check_metadata(kernel, checks);

  // k(x, x) scale for relative tolerances.
  const Eigen::VectorXd diagonal = kernel.diagonal(points);
  const double scale = diagonal.maxCoeff();
  checks.add("diagonal", scale > 0 && diagonal.minCoeff() >= 0,
             fmt::format("k(x, x) in [{}, {}]", g(diagonal.minCoeff()), g(scale)));
  if (!(scale > 0)) return report;  // every other tolerance is relative to it

  check_pairs(kernel, points, scale, checks);
  if (!check_matrices(kernel, points, scale, checks)) return report;

  if (domain.dimension == 1) {
    check_derivatives(kernel, scale, checks);
  } else {
    checks.skip("derivative", "defined for sections along a track (d = 1)");
    checks.skip("basis derivative", "defined for sections along a track (d = 1)");
    check_gradient(kernel, scale, checks, [&](std::size_t count, double start) {
      return scattered_points(domain, count, start);
    });
  }

  check_power_function(kernel, scale, checks, report);
  return report;
}

}  // namespace rkhs
