// The periodised Gaussian against its Fourier series (Poisson summation):
//   sum_m exp(-(d + m L)^2 / (2 sigma^2))
//     = (sigma sqrt(2 pi) / L) sum_k exp(-2 pi^2 sigma^2 k^2 / L^2) cos(2 pi k d / L).

#include <catch2/catch.hpp>
#include <cmath>

#include "kernel_test_support.hpp"
#include "rkhs/kernels/gaussian.hpp"

namespace {

using rkhs::kernels::Gaussian;
using rkhs::test::pi;

double fourier_series(double sigma, double length, double d) {
  double sum = 1.0;  // k = 0
  for (int k = 1; k < 100000; ++k) {
    const double decay = std::exp(-2 * pi * pi * sigma * sigma * k * k / (length * length));
    if (decay < 1e-30) break;
    sum += 2 * decay * std::cos(2 * pi * k * d / length);
  }
  return sigma * std::sqrt(2 * pi) / length * sum;
}

}  // namespace

TEST_CASE("periodised Gaussian equals its Fourier series", "[kernel][gaussian]") {
  for (double length : {rkhs::test::track_length, 25.0}) {
    const rkhs::Domain track{length, true};
    for (double sigma : {0.5, 1.0, 5.0, 50.0}) {
      for (const char* convention : {"2sigma2", "sigma2"}) {
        const auto kernel = rkhs::test::make_kernel_of<Gaussian>(
            {{"sigma", sigma}, {"convention", std::string(convention)}}, track);
        // exp(-d^2 / sigma^2) is the 2 sigma^2 convention with sigma / sqrt(2).
        const double width = std::string(convention) == "sigma2" ? sigma / std::sqrt(2.0) : sigma;
        const double at_zero = fourier_series(width, length, 0.0);
        double worst = 0;
        for (double d = -0.5 * length; d <= 0.5 * length; d += length / 97)
          worst =
              std::max(worst, std::abs(kernel(3.0 + d, 3.0) - fourier_series(width, length, d)));
        INFO("L " << length << " sigma " << sigma << " " << convention << " images "
                  << kernel.image_count() << " error " << worst << " k(0) " << at_zero);
        CHECK(worst <= 1e-13 * at_zero);
      }
    }
  }
}

TEST_CASE("Gaussian image count is finite and adapts to the width", "[kernel][gaussian]") {
  const rkhs::Domain paper_track{25.0, true};
  const auto narrow = rkhs::test::make_kernel_of<Gaussian>({{"sigma", 0.5}}, paper_track);
  const auto wide = rkhs::test::make_kernel_of<Gaussian>({{"sigma", 50.0}}, paper_track);
  CHECK(narrow.image_count() <= 1);
  // exp(-((M + 1/2) L)^2 / (2 sigma^2)) ~ 1e-16 needs M + 1/2 ~ 17 for sigma = 50, L = 25.
  CHECK(wide.image_count() >= 15);
  CHECK(wide.image_count() <= 40);
  const rkhs::Domain interval{25.0, false};
  const auto plain = rkhs::test::make_kernel_of<Gaussian>({{"sigma", 2.0}}, interval);
  CHECK(plain.image_count() == 0);
  CHECK(plain(1.0, 4.0) == Approx(std::exp(-9.0 / 8.0)).epsilon(1e-15));
  CHECK(plain(0.0, 25.0) == Approx(std::exp(-625.0 / 8.0)).epsilon(1e-15));
}

TEST_CASE("Gaussian kernel metadata", "[kernel][gaussian]") {
  const rkhs::Domain track{rkhs::test::track_length, true};
  const auto props = rkhs::test::make_kernel_of<Gaussian>({}, track).properties();
  CHECK(props.positive_definite);
  CHECK(props.analytic);
  CHECK_FALSE(props.sobolev_order.has_value());
  CHECK(props.support_radius == 0.0);
  CHECK(props.stationary);
  CHECK(props.periodic);
}
