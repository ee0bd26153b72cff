// Invalid kernel parameters fail with a ParameterError that names the parameter, whether the
// declaration (ParameterSet::resolve) or the kernel's constructor catches them.

#include <catch2/catch.hpp>
#include <string>

#include "kernel_test_support.hpp"
#include "rkhs/kernel/kernel.hpp"

namespace {

using rkhs::test::Given;

// The name of the parameter blamed when creating `kernel` with `given` on `domain`, or "" if it
// was accepted.
std::string blamed_parameter(const std::string& kernel, const Given& given,
                             const rkhs::Domain& domain) {
  try {
    rkhs::test::make_registered_kernel(kernel, given, domain);
  } catch (const rkhs::ParameterError& error) {
    INFO(error.what());
    CHECK(std::string(error.what()).find(error.parameter()) != std::string::npos);
    return error.parameter();
  }
  return "";
}

}  // namespace

TEST_CASE("invalid kernel parameters are rejected naming the parameter", "[kernel][parameters]") {
  const rkhs::Domain track{rkhs::test::track_length, true};
  const rkhs::Domain interval{rkhs::test::track_length, false};

  CHECK(blamed_parameter("bspline", {{"degree", std::int64_t{4}}}, track) == "degree");
  CHECK(blamed_parameter("bspline", {{"degree", std::int64_t{-1}}}, interval) == "degree");
  CHECK(blamed_parameter("bspline", {{"J", std::int64_t{17}}}, track) == "J");
  // Each in range, together 1.07e9 knots (4 GB to validate): refused before anything is built.
  CHECK(blamed_parameter("bspline", {{"n0", std::int64_t{8192}}, {"J", std::int64_t{16}}}, track) ==
        "J");
  // 8192 (2^11 - 1) = 16769024 knots are within 2^24 (not built here: 130 MB); one level more is
  // not.
  CHECK(blamed_parameter("bspline", {{"n0", std::int64_t{8192}}, {"J", std::int64_t{11}}}, track) ==
        "J");
  CHECK(blamed_parameter("bspline", {{"r", 0.0}}, track) == "r");
  CHECK(blamed_parameter("bspline", {{"n0", std::int64_t{0}}}, interval) == "n0");
  // Degree 0 defaults to r = 0, which is not > 0: r must be given.
  CHECK(blamed_parameter("bspline", {{"degree", std::int64_t{0}}}, track) == "r");
  CHECK(blamed_parameter("bspline", {{"degree", std::int64_t{0}}, {"r", 0.6}}, track).empty());
  // A periodic spline must not overlap itself: n0 >= degree + 1; the interval has no such limit.
  CHECK(blamed_parameter("bspline", {{"degree", std::int64_t{2}}, {"n0", std::int64_t{2}}},
                         track) == "n0");
  CHECK(blamed_parameter("bspline", {{"degree", std::int64_t{3}}, {"n0", std::int64_t{3}}},
                         track) == "n0");
  CHECK(blamed_parameter("bspline", {{"degree", std::int64_t{3}}, {"n0", std::int64_t{4}}}, track)
            .empty());
  CHECK(
      blamed_parameter("bspline", {{"degree", std::int64_t{3}}, {"n0", std::int64_t{1}}}, interval)
          .empty());

  CHECK(blamed_parameter("matern", {{"nu", 1.0}}, track) == "nu");
  CHECK(blamed_parameter("matern", {{"nu", std::int64_t{2}}}, track) == "nu");
  CHECK(blamed_parameter("matern", {{"nu", std::int64_t{3}}, {"length_scale", 1.0}}, track) ==
        "nu");
  CHECK(blamed_parameter("matern", {{"length_scale", -1.0}}, track) == "length_scale");
  CHECK(blamed_parameter("matern", {{"nu", 2.5}}, track).empty());

  CHECK(blamed_parameter("gaussian", {{"sigma", 0.0}}, track) == "sigma");
  CHECK(blamed_parameter("gaussian", {{"convention", std::string("sigma")}}, track) ==
        "convention");
  CHECK(blamed_parameter("gaussian", {{"width", 1.0}}, track) == "width");  // unknown parameter

  CHECK(blamed_parameter("wendland", {{"k", std::int64_t{4}}}, track) == "k");
  CHECK(blamed_parameter("wendland", {{"radius", -2.0}}, interval) == "radius");
}

TEST_CASE("the B-spline r defaults to the degree unless given", "[kernel][parameters]") {
  const rkhs::Domain track{rkhs::test::track_length, true};
  for (std::int64_t degree = 1; degree <= 3; ++degree) {
    auto kernel = rkhs::test::make_registered_kernel("bspline", {{"degree", degree}}, track);
    REQUIRE(kernel->properties().sobolev_order.has_value());
    CHECK(*kernel->properties().sobolev_order == static_cast<double>(degree));
  }
  auto given = rkhs::test::make_registered_kernel(
      "bspline", {{"degree", std::int64_t{2}}, {"r", 1.25}}, track);
  CHECK(*given->properties().sobolev_order == 1.25);
  // Outside (1/2, p + 1/2) the native space is not equivalent to a Sobolev space.
  auto rough = rkhs::test::make_registered_kernel("bspline",
                                                  {{"degree", std::int64_t{1}}, {"r", 1.5}}, track);
  CHECK_FALSE(rough->properties().sobolev_order.has_value());
}
