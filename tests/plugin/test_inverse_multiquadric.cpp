// The example plugin's kernel (examples/kernel-plugin): its Fourier-series periodisation equals the
// sum of images it replaces, and it refuses beta <= 1/2 on a closed track, where that sum diverges.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "plugin_test_support.hpp"
#include "rkhs/kernel/kernel.hpp"

using namespace rkhs;

namespace {

// Needs the plugin loaded (a test::ScopedPlugin declared before the kernel).
std::unique_ptr<AnyKernel> imq(double beta, double c, const Domain& domain) {
  const auto* entry = kernel_registry().find("inverse_multiquadric");
  REQUIRE(entry);
  return entry->factory(ParameterSet::resolve(entry->info.parameters, {{"beta", beta}, {"c", c}}),
                        domain);
}

}  // namespace

TEST_CASE("the periodic inverse multiquadric equals its sum of images", "[plugin][imq]") {
  const test::ScopedPlugin plugin(test::test_plugin("inverse_multiquadric"));
  const double length = 10.0;
  const Domain track{length, true};
  for (double beta : {0.75, 1.0, 2.5}) {
    for (double c : {0.3, 1.0, 4.0}) {
      auto kernel = imq(beta, c, track);
      for (double d : {0.0, 0.37, 1.9, 5.0}) {
        // Images |m| <= M summed from the smallest; the tail sum_{|m| > M} (c/(mL))^{2 beta} is
        // added in closed form through the Hurwitz-zeta integral bound (error << tolerance).
        const int images = 200000;
        double sum = 0;
        for (int m = images; m >= 1; --m)
          for (double shifted : {d + m * length, d - m * length}) {
            const double r = shifted / c;
            sum += std::pow(1.0 + r * r, -beta);
          }
        sum += std::pow(1.0 + (d / c) * (d / c), -beta);
        const double tail = 2.0 * std::pow(c / length, 2 * beta) *
                            std::pow(images + 0.5, 1 - 2 * beta) / (2 * beta - 1);
        INFO("beta = " << beta << ", c = " << c << ", d = " << d << ", tail ~ " << tail);
        CHECK(kernel->evaluate(d, 0.0) == Approx(sum + tail).epsilon(1e-9));
      }
    }
  }
}

TEST_CASE("the inverse multiquadric needs beta > 1/2 on a closed track only", "[plugin][imq]") {
  const test::ScopedPlugin plugin(test::test_plugin("inverse_multiquadric"));
  CHECK_THROWS_WITH(imq(0.5, 1.0, Domain{10.0, true}),
                    "parameter 'beta' must be > 1/2 on a closed track (the sum of the images of "
                    "(1 + (d/c)^2)^(-beta) diverges for beta <= 1/2), found 0.5");
  auto kernel = imq(0.5, 1.0, Domain{10.0, false});
  CHECK(kernel->evaluate(0.0, 1.0) == Approx(1.0 / std::sqrt(2.0)).epsilon(1e-15));
  CHECK(kernel->evaluate(2.0, 2.0) == 1.0);
}
