// verify-plugin's checks: every built-in kernel passes them with its defaults (so the rate
// tolerance is not too tight), and a kernel that lies about its smoothness or definiteness fails
// them (so they can fail).
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "plugin_test_support.hpp"
#include "rkhs/kernel/kernel_algorithms.hpp"
#include "rkhs/plugin/kernel_contract.hpp"
#include "rkhs/verify/plugin_verification.hpp"
#include "rkhs/plugin/plugin_kinds.hpp"

using namespace rkhs;

namespace {

const ContractCheck& theory_check(const KernelVerification& v, const std::string& name) {
  for (const auto& c : v.theory)
    if (c.name == name) return c;
  FAIL("no theory check " << name);
  throw;
}

// Matern nu = 1/2 (exp(-|d|), Sobolev order 1), declared with another order or as analytic.
template <int Declared>
struct MisdeclaredExponential {
  static PluginInfo info() {
    return {Declared == 0 ? "test_exponential_claims_analytic" : "test_exponential_claims_order_3",
            "exp(-|d|) with a wrong smoothness",
            {},
            {}};
  }
  MisdeclaredExponential(const ParameterSet&, const Domain& domain) : domain_(domain) {}
  double operator()(double x, double y) const noexcept {
    // Periodised exactly: sum_m exp(-|d + m L|) = cosh(L/2 - |d|) / sinh(L/2).
    const double d = std::abs(domain_.difference(x, y));
    if (!domain_.periodic) return std::exp(-d);
    return std::cosh(0.5 * domain_.length - d) / std::sinh(0.5 * domain_.length);
  }
  KernelProperties properties() const noexcept {
    KernelProperties p;
    if (Declared == 0)
      p.analytic = true;
    else
      p.sobolev_order = Declared;
    p.periodic = domain_.periodic;
    return p;
  }
  Domain domain_;
};

// Positive semidefinite but not strictly: rank 3 (cos(x - y) = cos x cos y + sin x sin y, plus 1).
struct RankThree {
  static PluginInfo info() { return {"test_rank_three", "1 + cos(2 pi (x - y) / L)", {}, {}}; }
  RankThree(const ParameterSet&, const Domain& domain) : domain_(domain) {}
  double operator()(double x, double y) const noexcept {
    return 1.0 + std::cos(2 * 3.14159265358979323846 * (x - y) / domain_.length);
  }
  KernelProperties properties() const noexcept {
    KernelProperties p;
    p.analytic = true;
    p.periodic = domain_.periodic;
    return p;
  }
  Domain domain_;
};

template <class K>
struct Scoped {
  Scoped() { REQUIRE(register_kernel<K>()); }
  ~Scoped() { kernel_registry().remove(K::info().name); }
};

}  // namespace

TEST_CASE("every built-in kernel passes verify-plugin's checks with its defaults",
          "[plugin][verify]") {
  for (const auto builtin : KernelKind::builtins) {
    const std::string name(builtin);
    const auto v = verify_kernel(name);
    INFO(name << " (" << v.parameters << "): " << v.declared);
    for (const auto& [where, report] : v.contract)
      for (const auto& failure : report.failures()) FAIL_CHECK(where << ": " << failure);
    for (const auto& c : v.theory) {
      INFO(c.name << ": " << c.detail);
      CHECK(c.passed);
    }
    CHECK(v.passed());
    const auto& rate = theory_check(v, "power-function rate");
    CHECK_FALSE(rate.skipped);  // every built-in declares its smoothness
  }
}

TEST_CASE("a kernel whose declared smoothness is wrong fails the rate check", "[plugin][verify]") {
  {
    Scoped<MisdeclaredExponential<3>> scoped;
    const auto v = verify_kernel("test_exponential_claims_order_3");
    const auto& rate = theory_check(v, "power-function rate");
    INFO(rate.detail);
    CHECK_FALSE(rate.passed);
    CHECK_THAT(rate.detail,
               Catch::StartsWith("Sobolev order 3: expected P_n ~ n^-2.50, measured n^-0.50"));
    CHECK_FALSE(v.passed());
  }
  {
    Scoped<MisdeclaredExponential<0>> scoped;
    const auto v = verify_kernel("test_exponential_claims_analytic");
    const auto& rate = theory_check(v, "power-function rate");
    INFO(rate.detail);
    CHECK_FALSE(rate.passed);  // algebraic n^-1/2: a power law fits better
  }
  {
    Scoped<MisdeclaredExponential<1>> scoped;  // the truth: tau = 1, P_n ~ n^-1/2
    const auto v = verify_kernel("test_exponential_claims_order_3");
    INFO(theory_check(v, "power-function rate").detail);
    CHECK(v.passed());
  }
}

TEST_CASE("a kernel declared strictly positive definite with a rank-3 Gram matrix fails",
          "[plugin][verify]") {
  Scoped<RankThree> scoped;
  const auto v = verify_kernel("test_rank_three");
  const auto& definite = theory_check(v, "strictly positive definite");
  INFO(definite.detail);
  CHECK_FALSE(definite.passed);
  // The contract itself holds: the kernel is positive semidefinite, symmetric, periodic.
  for (const auto& [where, report] : v.contract) CHECK(report.failures().empty());
}

TEST_CASE("the contract fails a kernel that is not symmetric or not positive semidefinite",
          "[plugin][verify]") {
  struct Asymmetric {
    static PluginInfo info() { return {"test_asymmetric", "exp(-(x-y)^2) + x/100", {}, {}}; }
    Asymmetric(const ParameterSet&, const Domain& domain) : domain_(domain) {}
    double operator()(double x, double y) const noexcept {
      return std::exp(-(x - y) * (x - y)) + x / 100;
    }
    KernelProperties properties() const noexcept {
      KernelProperties p;
      p.analytic = true;
      p.stationary = false;
      return p;
    }
    Domain domain_;
  };
  struct Box {  // the indicator of |d| < 1: not positive semidefinite
    static PluginInfo info() { return {"test_box", "1 if |d| < 1", {}, {}}; }
    Box(const ParameterSet&, const Domain& domain) : domain_(domain) {}
    double operator()(double x, double y) const noexcept {
      return std::abs(x - y) < 1.0 ? 1.0 : 0.0;
    }
    KernelProperties properties() const noexcept {
      KernelProperties p;
      p.sobolev_order = 1.0;
      p.support_radius = 1.0;
      return p;
    }
    Domain domain_;
  };
  const Domain interval{10.0, false};
  const auto asymmetric = check_kernel_contract(KernelModel<Asymmetric>(ParameterSet{}, interval));
  CHECK_FALSE(asymmetric.passed());
  CHECK_THAT(asymmetric.failures().front(), Catch::StartsWith("symmetry: "));
  const auto box = check_kernel_contract(KernelModel<Box>(ParameterSet{}, interval));
  CHECK_FALSE(box.passed());
  bool psd_failed = false;
  for (const auto& f : box.failures()) psd_failed |= f.starts_with("Gram positive semidefinite");
  CHECK(psd_failed);
  // Declared periodic-agnostic on a periodic domain: the periodicity claim is checked.
  const auto on_track = check_kernel_contract(KernelModel<Box>(ParameterSet{}, Domain{10.0, true}));
  bool periodicity_failed = false;
  for (const auto& f : on_track.failures())
    periodicity_failed |= f.starts_with("periodicity: declared periodic = no");
  CHECK(periodicity_failed);
}

TEST_CASE("verify-plugin on the example plugin passes and reports every check",
          "[plugin][verify]") {
  const auto v = verify_plugin(test::test_plugin("inverse_multiquadric"));
  CHECK(unload_plugin(v.plugin.file));
  REQUIRE(v.kernels.size() == 1);
  const auto text = format_verification(v);
  INFO(text);
  CHECK(v.passed());
  CHECK_THAT(text, Catch::Contains("kernel 'inverse_multiquadric' with its defaults (beta=1 c=1)"));
  CHECK_THAT(text,
             Catch::Contains("pass  power-function rate: analytic: exponential decay expected"));
  CHECK_THAT(text, Catch::Contains("pass  symmetry"));
  CHECK_THAT(text, Catch::Contains("pass  periodicity"));
  CHECK_THAT(text, Catch::Contains("pass  Gram positive semidefinite on random point sets"));
  CHECK_THAT(text,
             Catch::EndsWith("verify-plugin: PASS (36 checks: 31 passed, 5 skipped, 0 failed)\n"));
}
