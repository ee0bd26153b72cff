// The kernel contract, checked for every kernel in the registry (docs/style.md practice 6): a
// kernel registered tomorrow is tested with its default parameters the moment it registers; the
// built-in ones also with a few variants that stress their code paths (images, few features, wide
// support).

#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "plugins/kernels/kernel_test_support.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/kernel/kernel_algorithms.hpp"
#include "rkhs/plugin/kernel_contract.hpp"

namespace {

using rkhs::Domain;
using rkhs::test::Given;

std::vector<Given> variants_of(const std::string& name, bool periodic) {
  std::vector<Given> out{Given{}};
  if (name == "gaussian") {
    out.push_back({{"sigma", 0.5}});
    out.push_back({{"sigma", 3.0}, {"convention", std::string("sigma2")}});
    out.push_back({{"sigma", 50.0}});  // the paper's value: Gram singular to working precision
  } else if (name == "bspline") {
    out.push_back({{"degree", std::int64_t{0}}, {"r", 0.75}, {"J", std::int64_t{4}}});
    out.push_back({{"degree", std::int64_t{2}}});
    out.push_back({{"degree", std::int64_t{3}}, {"J", std::int64_t{3}}, {"r", 2.5}});
    // Six features on the periodic domain: Gram of 8 and 16 centres is rank deficient.
    out.push_back({{"degree", std::int64_t{1}}, {"n0", std::int64_t{2}}, {"J", std::int64_t{1}}});
    // n0 = degree + 1: the smallest periodic level, every spline covers the whole track.
    out.push_back({{"degree", std::int64_t{3}}, {"n0", std::int64_t{4}}, {"J", std::int64_t{2}}});
    if (!periodic)
      out.push_back({{"degree", std::int64_t{3}}, {"n0", std::int64_t{1}}, {"J", std::int64_t{2}}});
  } else if (name == "wendland") {
    out.push_back({{"k", std::int64_t{0}}, {"radius", 2.0}});
    out.push_back({{"k", std::int64_t{2}}, {"radius", 3.0}});
    out.push_back({{"k", std::int64_t{3}}, {"radius", 20.0}});  // wider than half the track
    out.push_back({{"k", std::int64_t{1}}, {"radius", 0.5}});   // narrower than the spacing
  } else if (name == "matern") {
    out.push_back({{"nu", 0.5}});
    out.push_back({{"nu", 2.5}, {"length_scale", 3.0}});
    out.push_back({{"nu", 0.5}, {"length_scale", 100.0}});  // many images
  }
  return out;
}

std::string describe(const std::string& name, const Given& given, const Domain& domain) {
  std::string out = name + (domain.periodic ? " (periodic)" : " (interval)");
  for (const auto& [key, value] : given) out += " " + key + "=" + rkhs::format_value(value);
  return out;
}

struct Tally {
  int kernels = 0;
  int monotonicity_checked = 0;  // nested comparisons whose tolerance made the check meaningful
};

// The checks themselves are the library's (rkhs/plugin/kernel_contract.hpp), shared with
// `rkhs-study verify-plugin`: one Catch2 assertion per named check.
void check_contract(const rkhs::AnyKernel& kernel, Tally& tally) {
  ++tally.kernels;
  const auto report = rkhs::check_kernel_contract(kernel);
  REQUIRE_FALSE(report.checks.empty());
  for (const auto& check : report.checks) {
    INFO(check.name << ": " << check.detail);
    CHECK(check.passed);
  }
  tally.monotonicity_checked += report.monotonicity_comparisons;
}

}  // namespace

TEST_CASE("every registered kernel satisfies the kernel contract", "[kernel][contract]") {
  const auto names = rkhs::kernel_registry().names();
  REQUIRE_FALSE(names.empty());
  Tally tally;
  for (bool periodic : {true, false}) {
    const Domain domain{rkhs::test::track_length, periodic};
    for (const auto& name : names) {
      for (const auto& given : variants_of(name, periodic)) {
        INFO(describe(name, given, domain));
        auto kernel = rkhs::test::make_registered_kernel(name, given, domain);
        CHECK(kernel->name() == name);
        check_contract(*kernel, tally);
      }
    }
  }
  // The monotonicity check must not be vacuous for most instances (ill-conditioned ones, such
  // as the Gaussian with sigma = 50, are legitimately skipped).
  INFO(tally.monotonicity_checked << " of " << 2 * tally.kernels << " nested comparisons checked");
  CHECK(tally.monotonicity_checked >= tally.kernels);
}

TEST_CASE("every kernel defined in d = 2 and 3 satisfies the contract on boxes and tori",
          "[kernel][contract][rd]") {
  // Variants sized for a box of extents 2, 1.5 (and 1): supports narrower and wider than it.
  const std::vector<std::pair<std::string, Given>> variants{
      {"gaussian", {}},
      {"gaussian", {{"sigma", 0.3}}},
      {"wendland", {}},
      {"wendland", {{"k", std::int64_t{0}}, {"radius", 0.7}}},
      {"wendland", {{"k", std::int64_t{2}}, {"radius", 2.5}}},
      {"wendland", {{"k", std::int64_t{3}}, {"radius", 0.4}}},
      {"matern", {}},
      {"matern", {{"nu", 0.5}, {"length_scale", 0.3}}},
      {"matern", {{"nu", 2.5}}}};
  Tally tally;
  int checked_instances = 0;
  for (int d = 2; d <= 3; ++d) {
    for (const bool periodic : {false, true}) {
      Domain domain{2.0, periodic};
      domain.dimension = d;
      domain.width = 1.5;
      domain.height = 1.0;
      for (const auto& [name, given] : variants) {
        if (name == "matern" && periodic) continue;  // refused on a torus (test_domains_in_rd)
        INFO(describe(name, given, domain) << " d = " << d);
        const auto kernel = rkhs::test::make_registered_kernel(name, given, domain);
        CHECK(kernel->properties().dimension == d);
        check_contract(*kernel, tally);
        ++checked_instances;
      }
    }
  }
  CHECK(checked_instances == 2 * (9 + 6));
  INFO(tally.monotonicity_checked << " nested comparisons checked");
  CHECK(tally.monotonicity_checked >= tally.kernels);
}

TEST_CASE("the contract in d = 3 fails a kernel that is positive definite on a line only",
          "[kernel][contract][rd]") {
  // cos(|x - y| / l) is positive semidefinite on R (cos(x - y) = cos x cos y + sin x sin y,
  // rank 2) and not on R^2 or R^3 (its Fourier transform there is a measure on a sphere of
  // radius 1/l, whose inverse transform of |x| changes sign): the Gram checks must catch it.
  struct CosineOfDistance {
    static rkhs::PluginInfo info() { return {"cosine_of_distance", "test kernel", {}, {}}; }
    CosineOfDistance(const rkhs::ParameterSet&, const Domain& domain) : domain_(domain) {}
    double operator()(double x, double y) const noexcept { return std::cos((x - y) / 0.2); }
    double operator()(const double* x, const double* y) const noexcept {
      return std::cos(std::sqrt(domain_.squared_distance(x, y)) / 0.2);
    }
    rkhs::KernelProperties properties() const noexcept {
      rkhs::KernelProperties p;
      p.positive_definite = false;
      p.analytic = true;
      p.dimension = domain_.dimension;
      return p;
    }
    Domain domain_;
  };
  Domain space{1.0, false};
  space.dimension = 3;
  space.width = 1.0;
  space.height = 1.0;
  const rkhs::KernelModel<CosineOfDistance> kernel(rkhs::ParameterSet{}, space);
  const auto report = rkhs::check_kernel_contract(kernel);
  CHECK_FALSE(report.passed());
  INFO(Catch::Detail::stringify(report.failures()));
  bool definiteness_failed = false;
  for (const auto& line : report.failures())
    definiteness_failed = definiteness_failed || line.find("Gram positive semidefinite") == 0;
  CHECK(definiteness_failed);
  // On a line the same kernel passes those checks.
  const rkhs::KernelModel<CosineOfDistance> on_line(rkhs::ParameterSet{}, Domain{1.0, false});
  for (const auto& line : rkhs::check_kernel_contract(on_line).failures())
    CHECK(line.find("Gram positive semidefinite") != 0);
}

namespace {

// A Gaussian that declares a two-dimensional domain, which no domain of this version has.
struct PlanarClaim {
  static rkhs::PluginInfo info() { return {"planar_claim", "test kernel", {}, {}}; }
  PlanarClaim(const rkhs::ParameterSet&, const Domain& domain) : domain_(domain) {}
  double operator()(double x, double y) const noexcept {
    const double d = domain_.difference(x, y);
    return std::exp(-d * d);
  }
  rkhs::KernelProperties properties() const noexcept {
    rkhs::KernelProperties p;
    p.analytic = true;
    p.periodic = domain_.periodic;
    p.dimension = 2;
    return p;
  }
  Domain domain_;
};

}  // namespace

TEST_CASE("the contract refuses a kernel that declares a dimension the domains do not have",
          "[kernel][contract]") {
  const rkhs::KernelModel<PlanarClaim> kernel(rkhs::ParameterSet{}, Domain{8.0, true});
  const auto report = rkhs::check_kernel_contract(kernel);
  bool metadata_checked = false;
  for (const auto& check : report.checks)
    if (check.name == "metadata") {
      metadata_checked = true;
      CHECK_FALSE(check.passed);
      CHECK_THAT(check.detail, Catch::Contains("dimension 2"));
    }
  CHECK(metadata_checked);
}

namespace {

// A Gaussian whose derivative() has the wrong sign: d/ds exp(-(s - c)^2 / 2) is -(s - c) k,
// this says +(s - c) k.
struct WrongSlope {
  static rkhs::PluginInfo info() { return {"wrong_slope", "test kernel", {}, {}}; }
  WrongSlope(const rkhs::ParameterSet&, const Domain& domain) : domain_(domain) {}
  double operator()(double x, double y) const noexcept {
    const double d = x - y;
    return std::exp(-0.5 * d * d);
  }
  double derivative(double x, double y) const noexcept { return (y - x) * (*this)(x, y); }
  rkhs::KernelProperties properties() const noexcept {
    rkhs::KernelProperties p;
    p.analytic = true;
    p.periodic = false;
    return p;
  }
  Domain domain_;
};

// The same Gaussian with the right derivative, and with none (the difference quotient).
struct RightSlope : WrongSlope {
  static rkhs::PluginInfo info() { return {"right_slope", "test kernel", {}, {}}; }
  using WrongSlope::WrongSlope;
  double derivative(double x, double y) const noexcept { return (x - y) * (*this)(x, y); }
};
struct NoSlope {
  static rkhs::PluginInfo info() { return {"no_slope", "test kernel", {}, {}}; }
  NoSlope(const rkhs::ParameterSet&, const Domain&) {}
  double operator()(double x, double y) const noexcept {
    const double d = x - y;
    return std::exp(-0.5 * d * d);
  }
  rkhs::KernelProperties properties() const noexcept {
    rkhs::KernelProperties p;
    p.analytic = true;
    p.periodic = false;
    return p;
  }
};

const rkhs::ContractCheck* find_check(const rkhs::ContractReport& report, const std::string& name) {
  for (const auto& check : report.checks)
    if (check.name == name) return &check;
  return nullptr;
}

}  // namespace

TEST_CASE("the contract's derivative check fails a wrong derivative and passes right ones",
          "[kernel][contract][derivative]") {
  const Domain interval{10.0, false};
  const auto wrong =
      rkhs::check_kernel_contract(rkhs::KernelModel<WrongSlope>(rkhs::ParameterSet{}, interval));
  const auto* check = find_check(wrong, "derivative");
  REQUIRE(check != nullptr);
  INFO(check->detail);
  CHECK_FALSE(check->passed);
  CHECK_THAT(check->detail, Catch::Contains("closed form"));
  CHECK_FALSE(wrong.passed());

  for (const auto& report :
       {rkhs::check_kernel_contract(rkhs::KernelModel<RightSlope>(rkhs::ParameterSet{}, interval)),
        rkhs::check_kernel_contract(rkhs::KernelModel<NoSlope>(rkhs::ParameterSet{}, interval))}) {
    for (const char* name : {"derivative", "basis derivative"}) {
      const auto* right = find_check(report, name);
      REQUIRE(right != nullptr);
      INFO(name << ": " << right->detail);
      CHECK(right->passed);
      CHECK_FALSE(right->skipped);
    }
  }
}

namespace {

// A Gaussian on the plane whose gradient has the wrong sign in its second component.
struct WrongGradient {
  static rkhs::PluginInfo info() { return {"wrong_gradient", "test kernel", {}, {}}; }
  WrongGradient(const rkhs::ParameterSet&, const Domain& domain) : domain_(domain) {}
  double operator()(double x, double y) const noexcept {
    const double d = x - y;
    return std::exp(-0.5 * d * d);
  }
  double operator()(const double* x, const double* y) const noexcept {
    return std::exp(-0.5 * domain_.squared_distance(x, y));
  }
  void gradient(const double* x, const double* y, double* g) const noexcept {
    const double k = (*this)(x, y);
    g[0] = (x[0] - y[0]) * k;
    g[1] = (y[1] - x[1]) * k;  // the sign is wrong
  }
  rkhs::KernelProperties properties() const noexcept {
    rkhs::KernelProperties p;
    p.analytic = true;
    p.dimension = domain_.dimension;
    return p;
  }
  Domain domain_;
};

}  // namespace

TEST_CASE("the contract's gradient check fails a wrong gradient and passes the built-in ones",
          "[kernel][contract][gradient]") {
  Domain plane{2.0, false};
  plane.dimension = 2;
  plane.width = 2.0;
  const auto wrong =
      rkhs::check_kernel_contract(rkhs::KernelModel<WrongGradient>(rkhs::ParameterSet{}, plane));
  const auto* check = find_check(wrong, "gradient");
  REQUIRE(check != nullptr);
  INFO(check->detail);
  CHECK_FALSE(check->passed);
  CHECK_THAT(check->detail, Catch::Contains("closed form") && Catch::Contains("axis 2"));
  for (const std::string name : {"gaussian", "wendland", "matern", "bspline"}) {
    const auto* entry = rkhs::kernel_registry().find(name);
    REQUIRE(entry);
    const auto kernel =
        entry->factory(rkhs::ParameterSet::resolve(entry->info.parameters, {}), plane);
    const auto report = rkhs::check_kernel_contract(*kernel);
    const auto* right = find_check(report, "gradient");
    REQUIRE(right != nullptr);
    INFO(name << ": " << right->detail);
    CHECK(right->passed);
    CHECK_FALSE(right->skipped);
    CHECK_THAT(right->detail, Catch::Contains("closed form"));
  }
}

TEST_CASE("richardson_derivative: Ridders' extrapolation to near round-off",
          "[contract][derivative]") {
  double error = 0;
  const double slope =
      rkhs::richardson_derivative([](double t) { return std::sin(3 * t); }, 0.4, 0.5, error);
  CHECK(slope == Approx(3 * std::cos(1.2)).margin(1e-11));
  CHECK(error < 1e-9);
  // A narrow function from a wide starting step: the smaller starts find it.
  const double narrow = rkhs::richardson_derivative(
      [](double t) { return std::exp(-t * t / (2e-4)); }, 0.01, 2.0, error);
  CHECK(narrow == Approx(-0.01 / 1e-4 * std::exp(-1e-4 / 2e-4)).epsilon(1e-8));
}
