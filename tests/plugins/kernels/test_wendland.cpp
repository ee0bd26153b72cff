// Wendland's functions phi_{1,k} against values computed by hand, their compact support, and the
// periodised kernel against a brute-force image sum.

#include <catch2/catch.hpp>
#include <cmath>

#include "kernel_test_support.hpp"
#include "rkhs/kernels/wendland.hpp"

namespace {
using rkhs::kernels::Wendland;
}

TEST_CASE("Wendland functions take their known values", "[kernel][wendland]") {
  // phi_{1,k}(1/2), by hand from Wendland's Table 9.1:
  //   k=0: 1/2; k=1: (1/8)(5/2) = 5/16; k=2: (1/32)(2 + 5/2 + 1) = 11/64;
  //   k=3: (1/128)(21/8 + 19/4 + 7/2 + 1) = 95/1024.
  const double at_half[] = {0.5, 5.0 / 16, 11.0 / 64, 95.0 / 1024};
  const rkhs::Domain interval{rkhs::test::track_length, false};
  for (std::int64_t k = 0; k <= 3; ++k) {
    INFO("k " << k);
    const auto kernel = rkhs::test::make_kernel_of<Wendland>({{"k", k}, {"radius", 2.0}}, interval);
    CHECK(kernel(3.0, 4.0) == Approx(at_half[k]).epsilon(1e-15));
    CHECK(kernel(4.0, 3.0) == Approx(at_half[k]).epsilon(1e-15));
    CHECK(kernel(3.0, 3.0) == 1.0);
    CHECK(kernel(3.0, 5.0) == 0.0);  // r = 1
    CHECK(kernel(3.0, 5.0001) == 0.0);
    CHECK(kernel(3.0, 9.0) == 0.0);
    CHECK(kernel(3.0, 4.999) > 0.0);
    // phi is C^{2k}, so it vanishes at r = 1 to order 2k + 1: phi(1 - e) ~ e^{2k+1}.
    const double e = 1e-3;
    const double ratio = Wendland::phi(static_cast<int>(k), 1 - e) / std::pow(e, 2 * k + 1);
    CHECK(ratio > 0.1);
    CHECK(ratio < 1e3);
  }
}

TEST_CASE("periodised Wendland kernels equal their image sums", "[kernel][wendland]") {
  const double length = rkhs::test::track_length;
  const rkhs::Domain track{length, true};
  for (std::int64_t k = 0; k <= 3; ++k) {
    for (double radius : {1.0, 0.5 * length, 0.6 * length, 3.3 * length}) {
      const auto kernel =
          rkhs::test::make_kernel_of<Wendland>({{"k", k}, {"radius", radius}}, track);
      double worst = 0;
      for (double d = -0.5 * length; d <= 0.5 * length; d += length / 83) {
        double expected = 0;
        for (int m = -20; m <= 20; ++m)
          expected += Wendland::phi(static_cast<int>(k), std::abs(d + m * length) / radius);
        worst = std::max(worst, std::abs(kernel(d + 0.5, 0.5) - expected));
      }
      INFO("k " << k << ", radius " << radius << ", error " << worst);
      CHECK(worst <= 1e-14 * (1 + 2 * radius / length));
      // Zero beyond the support radius, measured along the circle.
      if (radius < 0.5 * length) CHECK(kernel(0.5, 0.5 + radius * 1.001) == 0.0);
    }
  }
}

TEST_CASE("Wendland kernel metadata", "[kernel][wendland]") {
  const rkhs::Domain track{rkhs::test::track_length, true};
  for (std::int64_t k = 0; k <= 3; ++k) {
    const auto props =
        rkhs::test::make_kernel_of<Wendland>({{"k", k}, {"radius", 1.5}}, track).properties();
    CHECK(props.positive_definite);
    CHECK(props.sobolev_order == static_cast<double>(k) + 1.0);
    CHECK(props.support_radius == 1.5);
    CHECK(props.stationary);
    CHECK(props.periodic);
  }
}
