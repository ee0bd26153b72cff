// Matern kernels against scikit-learn's formulas, and the periodised nu = 1/2 kernel against its
// closed form: sum_m exp(-|d + m L| / l) = cosh((L/2 - |d|) / l) / sinh(L / (2 l)), |d| <= L/2.

#include <catch2/catch.hpp>
#include <cmath>

#include "kernel_test_support.hpp"
#include "rkhs/kernels/matern.hpp"

namespace {

using rkhs::kernels::Matern;

// Brute-force image sum, far more images than the kernel needs.
template <class Profile>
double many_images(const Profile& profile, double d, double length, int images) {
  double sum = 0;
  for (int m = -images; m <= images; ++m) sum += profile(std::abs(d + m * length));
  return sum;
}

}  // namespace

TEST_CASE("Matern kernels take scikit-learn's values", "[kernel][matern]") {
  const rkhs::Domain interval{rkhs::test::track_length, false};
  const auto half =
      rkhs::test::make_kernel_of<Matern>({{"nu", 0.5}, {"length_scale", 2.0}}, interval);
  const auto three_halves =
      rkhs::test::make_kernel_of<Matern>({{"nu", 1.5}, {"length_scale", 0.7}}, interval);
  const auto five_halves =
      rkhs::test::make_kernel_of<Matern>({{"nu", 2.5}, {"length_scale", 3.0}}, interval);
  CHECK(half(1.0, 2.3) == Approx(std::exp(-0.65)).epsilon(1e-15));
  const double a = std::sqrt(3.0) * 0.4 / 0.7;
  CHECK(three_halves(5.4, 5.0) == Approx((1 + a) * std::exp(-a)).epsilon(1e-15));
  const double b = std::sqrt(5.0) * 2.0 / 3.0;
  CHECK(five_halves(2.0, 4.0) ==
        Approx((1 + b + 5.0 * 4.0 / (3.0 * 9.0)) * std::exp(-b)).epsilon(1e-15));
  // The default (nu = 1.5, l = 1) at d = 1: (1 + sqrt 3) exp(-sqrt 3), evaluated separately.
  const auto unit = rkhs::test::make_kernel_of<Matern>({}, interval);
  CHECK(unit(0.0, 1.0) == Approx(0.4833577245965077).epsilon(1e-14));
  CHECK(unit(7.0, 7.0) == 1.0);
}

TEST_CASE("periodised Matern kernels equal their image sums", "[kernel][matern]") {
  const double length = rkhs::test::track_length;
  const rkhs::Domain track{length, true};
  for (double l : {0.3, 1.0, 10.0, 100.0, 1000.0}) {
    const auto kernel =
        rkhs::test::make_kernel_of<Matern>({{"nu", 0.5}, {"length_scale", l}}, track);
    double worst = 0;
    for (double d = -0.5 * length; d <= 0.5 * length; d += length / 89) {
      const double closed =
          std::cosh((0.5 * length - std::abs(d)) / l) / std::sinh(0.5 * length / l);
      worst = std::max(worst, std::abs(kernel(d + 1.0, 1.0) - closed));
    }
    const double at_zero = 1.0 / std::tanh(0.5 * length / l);
    INFO("nu 0.5, l " << l << ", error " << worst);
    CHECK(worst <= 1e-13 * at_zero);
  }
  for (double nu : {1.5, 2.5}) {
    for (double l : {0.5, 5.0, 60.0, 1000.0}) {
      const auto kernel =
          rkhs::test::make_kernel_of<Matern>({{"nu", nu}, {"length_scale", l}}, track);
      const double c = std::sqrt(2 * nu) / l;
      auto profile = [&](double r) {
        const double a = c * r;
        return nu == 1.5 ? (1 + a) * std::exp(-a) : (1 + a + a * a / 3) * std::exp(-a);
      };
      double worst = 0;
      const double at_zero = many_images(profile, 0.0, length, 5000);
      for (double d = -0.5 * length; d <= 0.5 * length; d += length / 89)
        worst =
            std::max(worst, std::abs(kernel(d + 2.0, 2.0) - many_images(profile, d, length, 5000)));
      INFO("nu " << nu << ", l " << l << ", error " << worst);
      CHECK(worst <= 1e-13 * at_zero);
    }
  }
}

TEST_CASE("Matern kernel metadata", "[kernel][matern]") {
  const rkhs::Domain track{rkhs::test::track_length, true};
  for (double nu : {0.5, 1.5, 2.5}) {
    const auto props = rkhs::test::make_kernel_of<Matern>({{"nu", nu}}, track).properties();
    CHECK(props.positive_definite);
    CHECK_FALSE(props.analytic);
    CHECK(props.sobolev_order == nu + 0.5);
    CHECK(props.support_radius == 0.0);
    CHECK(props.stationary);
  }
}
