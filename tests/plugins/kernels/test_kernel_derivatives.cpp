// Derivatives of the built-in kernels' sections, d/ds k(c, s): the closed forms against values
// worked out by hand, against central differences (periodised kernels), the B-spline's
// right-hand derivative at a knot and its feature derivatives, and every basis' derivatives
// against AnyKernel::derivative (and their mapped form against T dphi).

#include <Eigen/Dense>
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "kernel_test_support.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/kernels/bspline.hpp"
#include "rkhs/kernels/gaussian.hpp"
#include "rkhs/kernels/matern.hpp"
#include "rkhs/kernels/wendland.hpp"

namespace {

using rkhs::Domain;
using rkhs::test::Given;

const Domain interval{20.0, false};
const Domain track{rkhs::test::track_length, true};

// (k(c, s + h) - k(c, s - h)) / 2h, h = 1e-5: truncation h^2 |k'''| / 6 ~ 1e-10 for the widths
// used here, rounding eps k / h ~ 1e-11.
template <class K>
double central_difference(const K& kernel, double c, double s, double h = 1e-5) {
  return (kernel(c, s + h) - kernel(c, s - h)) / (2 * h);
}

}  // namespace

TEST_CASE("Gaussian derivative: -(s - c) / sigma^2 k, and -2 (s - c) / sigma^2 k for sigma2",
          "[kernel][derivative][gaussian]") {
  const double sigma = 0.7;
  const auto halves =
      rkhs::test::make_kernel_of<rkhs::kernels::Gaussian>({{"sigma", sigma}}, interval);
  const auto whole = rkhs::test::make_kernel_of<rkhs::kernels::Gaussian>(
      {{"sigma", sigma}, {"convention", std::string("sigma2")}}, interval);
  for (double c : {3.0, 10.0}) {
    for (double s : {2.0, 3.0, 3.4, 4.9, 10.0, 11.5}) {
      INFO("c = " << c << ", s = " << s);
      const double k_half = std::exp(-(s - c) * (s - c) / (2 * sigma * sigma));
      const double k_whole = std::exp(-(s - c) * (s - c) / (sigma * sigma));
      CHECK(halves.derivative(c, s) == Approx(-(s - c) / (sigma * sigma) * k_half).margin(1e-15));
      CHECK(whole.derivative(c, s) ==
            Approx(-2 * (s - c) / (sigma * sigma) * k_whole).margin(1e-15));
    }
  }
  // Periodised: the sum of the images' derivatives, against a difference of the image sum.
  for (double width : {0.5, 3.0, 50.0}) {
    const auto periodic =
        rkhs::test::make_kernel_of<rkhs::kernels::Gaussian>({{"sigma", width}}, track);
    for (double s : {0.3, 5.0, 12.0, 20.0, 25.0}) {
      INFO("sigma = " << width << ", s = " << s);
      CHECK(periodic.derivative(1.0, s) ==
            Approx(central_difference(periodic, 1.0, s)).margin(1e-9));
      CHECK(periodic.derivative(1.0, s + track.length) ==
            Approx(periodic.derivative(1.0, s)).margin(1e-13));
    }
  }
}

TEST_CASE("Wendland derivative: phi'(r) / rho with the sign of s - c",
          "[kernel][derivative][wendland]") {
  const double rho = 2.0;
  // d/dr of (1 - r)^l p(r), worked out by hand.
  auto slope = [](int k, double r) {
    const double s = 1 - r;
    switch (k) {
      case 0:
        return -1.0;
      case 1:
        return -12 * r * s * s;
      case 2:
        return -14 * r * (4 * r + 1) * std::pow(s, 4);
      default:
        return -6 * r * (35 * r * r + 18 * r + 3) * std::pow(s, 6);
    }
  };
  for (std::int64_t k = 0; k <= 3; ++k) {
    const auto kernel =
        rkhs::test::make_kernel_of<rkhs::kernels::Wendland>({{"k", k}, {"radius", rho}}, interval);
    const double c = 8.0;
    for (double s : {6.3, 7.5, 8.4, 9.9}) {
      const double r = std::abs(s - c) / rho;
      const double expected = (s > c ? 1.0 : -1.0) * slope(static_cast<int>(k), r) / rho;
      INFO("k = " << k << ", s = " << s);
      CHECK(kernel.derivative(c, s) == Approx(expected).margin(1e-15));
      CHECK(kernel.derivative(c, s) == Approx(central_difference(kernel, c, s)).margin(1e-9));
    }
    // Outside the support: 0.
    CHECK(kernel.derivative(c, c + 2.5) == 0.0);
    CHECK(kernel.derivative(c, c - 2.5) == 0.0);
  }
  // k = 0 has kinks at s = c and |s - c| = rho: the right-hand derivative in s.
  const auto hat = rkhs::test::make_kernel_of<rkhs::kernels::Wendland>(
      {{"k", std::int64_t{0}}, {"radius", rho}}, interval);
  CHECK(hat.derivative(8.0, 8.0) == -1.0 / rho);
  CHECK(hat.derivative(8.0, 8.0 - rho) == 1.0 / rho);
  CHECK(hat.derivative(8.0, 8.0 + rho) == 0.0);
  // Periodised, support wider than the track.
  for (std::int64_t k = 1; k <= 3; ++k) {
    const auto wide =
        rkhs::test::make_kernel_of<rkhs::kernels::Wendland>({{"k", k}, {"radius", 20.0}}, track);
    for (double s : {0.3, 5.0, 12.0, 20.0})
      CHECK(wide.derivative(1.0, s) == Approx(central_difference(wide, 1.0, s)).margin(1e-9));
  }
}

TEST_CASE("Matern derivative for nu = 1/2, 3/2, 5/2", "[kernel][derivative][matern]") {
  const double l = 1.5;
  const double c = 9.0;
  for (double nu : {0.5, 1.5, 2.5}) {
    const auto kernel = rkhs::test::make_kernel_of<rkhs::kernels::Matern>(
        {{"nu", nu}, {"length_scale", l}}, interval);
    for (double s : {6.0, 8.2, 9.5, 12.0}) {
      const double d = s - c, a = std::sqrt(2 * nu) * std::abs(d) / l;
      double expected = 0;
      if (nu == 0.5) expected = -(d > 0 ? 1.0 : -1.0) / l * std::exp(-a);
      if (nu == 1.5) expected = -3 * d / (l * l) * std::exp(-a);
      if (nu == 2.5) expected = -5.0 / 3.0 * d / (l * l) * (1 + a) * std::exp(-a);
      INFO("nu = " << nu << ", s = " << s);
      CHECK(kernel.derivative(c, s) == Approx(expected).margin(1e-15));
    }
    // At s = c: the right-hand derivative (-1 / l for nu = 1/2, 0 otherwise).
    CHECK(kernel.derivative(c, c) == (nu == 0.5 ? -1.0 / l : 0.0));
    // The closed-form image sums, against differences, including long length scales.
    for (double scale : {0.7, 3.0, 100.0}) {
      const auto periodic = rkhs::test::make_kernel_of<rkhs::kernels::Matern>(
          {{"nu", nu}, {"length_scale", scale}}, track);
      for (double s : {0.3, 5.0, 12.0, 13.566, 20.0}) {
        INFO("nu = " << nu << ", l = " << scale << ", s = " << s);
        CHECK(periodic.derivative(1.0, s) ==
              Approx(central_difference(periodic, 1.0, s)).margin(1e-8));
      }
    }
  }
}

TEST_CASE("B-spline derivative: values by hand, right-hand at a knot",
          "[kernel][derivative][bspline]") {
  // degree 1, one level, h0 = 2 on [0, 8]: for u, v in the first cell, x = u / 2 = 0.25 and
  // k = N_1(y) N_1(x) + N_1(y + 1) N_1(x + 1) = 0.25 y + 0.75 (1 - y), y = v / 2: dk/dv = -0.25.
  const Domain small{8.0, false};
  const auto hat = rkhs::test::make_kernel_of<rkhs::kernels::MultiscaleBSpline>(
      {{"degree", std::int64_t{1}}, {"n0", std::int64_t{4}}, {"J", std::int64_t{0}}}, small);
  CHECK(hat.derivative(0.5, 1.5) == Approx(-0.25).epsilon(1e-15));
  // At the knot v = 2 (y = 1) the derivative jumps from -0.25 (left) to -0.125 (right: of the
  // splines nonzero at u only N_1(y), falling on [1, 2), remains).
  CHECK(hat.derivative(0.5, 2.0) == Approx(-0.125).epsilon(1e-15));
  CHECK(hat.derivative(0.5, 2.0 - 1e-9) == Approx(-0.25).epsilon(1e-12));
  // At v = L on the interval: the left-hand derivative (the last cell's piece).
  CHECK(hat.derivative(7.5, 8.0) == Approx(hat.derivative(7.5, 7.9)).epsilon(1e-12));

  // Every degree, several levels, both domains: against differences inside the finest cells.
  for (const Domain& domain : {interval, track}) {
    for (std::int64_t degree = 0; degree <= 3; ++degree) {
      Given given{{"degree", degree}, {"J", std::int64_t{3}}};
      if (degree == 0) given["r"] = 0.75;
      const auto kernel =
          rkhs::test::make_kernel_of<rkhs::kernels::MultiscaleBSpline>(given, domain);
      const double cell = domain.length / (4 << 3);
      for (double u : {0.37, 5.5, 13.1}) {
        for (int i = 0; i < 32; i += 3) {
          const double v = (i + 0.37) * cell;
          INFO((domain.periodic ? "track" : "interval")
               << ", degree " << degree << ", u = " << u << ", v = " << v);
          CHECK(kernel.derivative(u, v) ==
                Approx(central_difference(kernel, u, v, 1e-3 * cell)).margin(1e-8));
        }
      }
    }
  }
}

TEST_CASE("B-spline feature derivatives: the indices of features(), d/du of their values",
          "[kernel][derivative][bspline]") {
  for (const Domain& domain : {interval, track}) {
    for (std::int64_t degree = 1; degree <= 3; ++degree) {
      const auto kernel = rkhs::test::make_kernel_of<rkhs::kernels::MultiscaleBSpline>(
          {{"degree", degree}, {"J", std::int64_t{4}}}, domain);
      rkhs::SparseFeatures at, slopes, ahead, behind;
      const double h = 1e-6;
      for (double u : {0.1234, 3.3, 11.0, 19.95}) {
        kernel.features(u, at);
        kernel.feature_derivatives(u, slopes);
        kernel.features(u + h, ahead);
        kernel.features(u - h, behind);
        REQUIRE(slopes.size() == at.size());
        for (std::size_t f = 0; f < at.size(); ++f) {
          INFO("degree " << degree << ", u = " << u << ", feature " << f);
          CHECK(slopes.index[f] == at.index[f]);
          // Same cell at u +- h for these u: the features' own differences.
          if (ahead.index == at.index && behind.index == at.index)
            CHECK(slopes.value[f] ==
                  Approx((ahead.value[f] - behind.value[f]) / (2 * h)).margin(1e-5));
        }
        // derivative(c, u) is the dot product of c's features with these.
        rkhs::SparseFeatures centre;
        kernel.features(7.1, centre);
        double dot = 0;
        for (std::size_t a = 0; a < centre.size(); ++a)
          for (std::size_t b = 0; b < slopes.size(); ++b)
            if (centre.index[a] == slopes.index[b]) dot += centre.value[a] * slopes.value[b];
        CHECK(kernel.derivative(7.1, u) == Approx(dot).margin(1e-12));
      }
    }
  }
}

namespace {

std::vector<Given> variants(const std::string& name) {
  if (name == "gaussian") return {{}, {{"sigma", 0.3}}, {{"sigma", 50.0}}};
  if (name == "wendland")
    return {{{"k", std::int64_t{0}}},
            {{"k", std::int64_t{1}}},
            {{"k", std::int64_t{3}}, {"radius", 20.0}}};
  if (name == "matern") return {{{"nu", 0.5}}, {{"nu", 1.5}}, {{"nu", 2.5}, {"length_scale", 4.0}}};
  if (name == "bspline")
    return {
        {}, {{"degree", std::int64_t{2}}}, {{"degree", std::int64_t{3}}, {"J", std::int64_t{2}}}};
  return {{}};
}

}  // namespace

TEST_CASE("every built-in kernel has exact derivatives, and its basis gives the same values",
          "[kernel][derivative][basis]") {
  for (const std::string name : {"gaussian", "wendland", "matern", "bspline"}) {
    for (const Domain& domain : {interval, track}) {
      for (const auto& given : variants(name)) {
        const auto kernel = rkhs::test::make_registered_kernel(name, given, domain);
        std::string description = name + (domain.periodic ? " (track)" : " (interval)");
        for (const auto& [key, value] : given)
          description += " " + key + "=" + rkhs::format_value(value);
        INFO(description);
        CHECK(kernel->has_exact_derivative());

        const auto centres = rkhs::test::scattered_points(9, domain.length, 0.77);
        const auto basis = kernel->basis(centres);
        // Points: scattered, the centres themselves, and the finest B-spline knots nearby.
        auto points = rkhs::test::scattered_points(23, domain.length, 0.05);
        points.insert(points.end(), centres.begin(), centres.end());
        const auto kinks = kernel->kink_points();
        for (std::size_t i = 0; i < kinks.size(); i += std::max<std::size_t>(1, kinks.size() / 7))
          points.push_back(kinks[i]);

        Eigen::VectorXd dphi(9);
        double slope_scale = 0;
        for (double s : points)
          for (double c : centres)
            slope_scale = std::max(slope_scale, std::abs(kernel->derivative(c, s)));
        // Nonzero for flat sections (sigma = 50 on the track): max k / L, as in the contract.
        for (double c : centres)
          slope_scale = std::max(slope_scale, kernel->evaluate(c, c) / domain.length);
        for (double s : points) {
          basis->evaluate_derivative(s, dphi.data());
          for (std::size_t i = 0; i < centres.size(); ++i) {
            INFO("s = " << s << ", centre " << centres[i]);
            CHECK(std::abs(dphi(static_cast<Eigen::Index>(i)) -
                           kernel->derivative(centres[i], s)) <= 1e-13 * slope_scale);
          }
        }

        // Mapped: a general map, a multiple of the identity (applied as a scalar by direct
        // bases) and the identity.
        Eigen::MatrixXd general(4, 9);
        for (Eigen::Index i = 0; i < 4; ++i)
          for (Eigen::Index j = 0; j < 9; ++j)
            general(i, j) = std::sin(1.0 + 3.0 * double(i) + 0.7 * double(j));
        for (const Eigen::MatrixXd& map :
             {general, Eigen::MatrixXd(2.5 * Eigen::MatrixXd::Identity(9, 9)),
              Eigen::MatrixXd(Eigen::MatrixXd::Identity(9, 9))}) {
          basis->set_map(map);
          Eigen::VectorXd mapped(map.rows());
          for (double s : points) {
            basis->evaluate_derivative(s, dphi.data());
            basis->evaluate_mapped_derivative(s, mapped.data());
            INFO("map " << map.rows() << " x " << map.cols() << ", s = " << s);
            CHECK((mapped - map * dphi).cwiseAbs().maxCoeff() <= 1e-13 * 9 * slope_scale);
          }
        }
      }
    }
  }
}
