#include "rkhs/verify/plugin_verification.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "rkhs/approx/approximation.hpp"
#include "rkhs/approx/centres.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/rates/rates.hpp"
#include "rkhs/approx/target.hpp"

namespace rkhs {

namespace {

constexpr double epsilon = std::numeric_limits<double>::epsilon();
/// The paper's track: a circle of radius 4 m.
constexpr double track_length = 2 * std::numbers::pi * 4;
constexpr std::size_t evaluation_points = 4096;

std::string g(double value) {
  return fmt::format("{:.3g}", value);
}

// The power-function sup at uniform centres, with the points at the round-off floor dropped.
struct Decay {
  std::vector<double> n, sup;
  std::size_t at_floor = 0;
};
Decay measure_decay(const KernelRegistry::Entry& entry, const Domain& domain,
                    const std::vector<std::size_t>& n_values) {
  const auto* sine = target_registry().find("sine");
  if (!sine) throw std::logic_error("the built-in target 'sine' is not registered");
  const auto target = sine->factory(ParameterSet::resolve(sine->info.parameters, {}), domain);
  const auto kernel = entry.factory(ParameterSet::resolve(entry.info.parameters, {}), domain);
  const auto& names = approximation_metric_names();
  const auto sup_index = static_cast<std::size_t>(
      std::find(names.begin(), names.end(), "power_function_sup") - names.begin());
  Decay decay;
  for (std::size_t n : n_values) {
    const auto centres = domain.uniform_points(n);
    const auto measured = measure_approximation(*kernel, *target, centres, evaluation_points, {});
    const bool floor = std::find(measured.flags.begin(), measured.flags.end(),
                                 "power_function_at_floor") != measured.flags.end();
    if (floor || !(measured.metrics[sup_index] > 0)) {
      ++decay.at_floor;
      continue;
    }
    decay.n.push_back(static_cast<double>(n));
    decay.sup.push_back(measured.metrics[sup_index]);
  }
  return decay;
}

std::string n_range(const std::vector<double>& n) {
  return n.empty() ? std::string("none") : fmt::format("n = {}..{}", n.front(), n.back());
}

ContractCheck rate_check(const KernelRegistry::Entry& entry, const KernelProperties& props,
                         const Domain& domain) {
  ContractCheck check{"power-function rate", true, false, ""};
  if (props.sobolev_order) {
    // sup P ~ h^(tau - d/2) and h ~ n^-1/d.
    const double d = props.dimension;
    const double expected = -(*props.sobolev_order - 0.5 * d) / d;
    auto decay = measure_decay(entry, domain, {16, 32, 64, 128, 256, 512, 1024});
    // The finest four points: the asymptotic regime.
    if (decay.n.size() > 4) {
      decay.n.erase(decay.n.begin(), decay.n.end() - 4);
      decay.sup.erase(decay.sup.begin(), decay.sup.end() - 4);
    }
    const auto fit = fit_power_law(decay.n, decay.sup);
    if (!fit) {
      check.passed = false;
      check.detail = fmt::format(
          "Sobolev order {}: expected P_n ~ n^{}, but fewer than two values "
          "of n are above the round-off floor ({} at the floor)",
          g(*props.sobolev_order), g(expected), decay.at_floor);
      return check;
    }
    check.passed = std::abs(fit->rate - expected) <= rate_tolerance;
    check.detail = fmt::format(
        "Sobolev order {}: expected P_n ~ n^{:.2f}, measured n^{:.2f} ({}, "
        "R^2 = {:.3f}; tolerance {:.2f})",
        g(*props.sobolev_order), expected, fit->rate, n_range(decay.n), fit->r_squared,
        rate_tolerance);
    return check;
  }
  if (props.analytic) {
    const auto decay = measure_decay(entry, domain, {8, 12, 16, 24, 32, 48, 64});
    const auto fit = fit_exponential(decay.n, decay.sup);
    const auto local = pairwise_rates(decay.n, decay.sup);
    if (!fit || decay.n.size() < 3) {
      check.passed = false;
      check.detail = fmt::format(
          "analytic: exponential decay expected, but only {} values of n "
          "are above the round-off floor",
          decay.n.size());
      return check;
    }
    const auto algebraic = fit_power_law(decay.n, decay.sup);
    const double first = local.front(), last = local.back();
    check.passed = fit->rate < 0 && last < first && fit->r_squared > algebraic->r_squared;
    check.detail = fmt::format(
        "analytic: exponential decay expected; measured P_n ~ exp({:.3f} n) "
        "({}, R^2 = {:.4f}; a power law: R^2 = {:.4f}), local power-law rate "
        "{:.2f} -> {:.2f} (must decay, fit exp(-c n) better than n^-r, and "
        "steepen)",
        fit->rate, n_range(decay.n), fit->r_squared, algebraic->r_squared, first, last);
    return check;
  }
  check.skipped = true;
  check.detail = "neither a Sobolev order nor analytic declared: no expected rate";
  return check;
}

ContractCheck strict_definiteness_check(const AnyKernel& kernel) {
  ContractCheck check{"strictly positive definite", true, false, ""};
  if (!kernel.properties().positive_definite) {
    check.skipped = true;
    check.detail = "not declared (positive semidefinite only)";
    return check;
  }
  const std::size_t n = 12;
  const auto lambda = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(
                          kernel.gram(kernel.domain().uniform_points(n)), Eigen::EigenvaluesOnly)
                          .eigenvalues();
  const double ratio = lambda.minCoeff() / lambda.maxCoeff();
  const double threshold = 1e3 * static_cast<double>(n) * epsilon;
  check.passed = ratio > threshold;
  check.detail = fmt::format("{} uniform centres: lambda_min / lambda_max = {} (must exceed {})", n,
                             g(ratio), g(threshold));
  return check;
}

std::string format_check(const ContractCheck& c) {
  const char* verdict = c.skipped ? "skip" : c.passed ? "pass" : "FAIL";
  return fmt::format("    {}  {}: {}\n", verdict, c.name, c.detail);
}

}  // namespace

bool KernelVerification::passed() const noexcept {
  return std::all_of(contract.begin(), contract.end(),
                     [](const auto& c) { return c.second.passed(); }) &&
         std::all_of(theory.begin(), theory.end(), [](const auto& c) { return c.passed; });
}

bool PluginVerification::passed() const noexcept {
  return std::all_of(kernels.begin(), kernels.end(), [](const auto& k) { return k.passed(); });
}

KernelVerification verify_kernel(std::string_view name) {
  const auto* entry = kernel_registry().find(name);
  if (!entry) throw std::invalid_argument(fmt::format("unknown kernel '{}'", name));
  KernelVerification out;
  out.kernel = std::string(name);
  const auto defaults = ParameterSet::resolve(entry->info.parameters, {});
  out.parameters = defaults.canonical();

  const Domain track{track_length, true}, interval{track_length, false};
  std::unique_ptr<AnyKernel> on_track;
  for (const auto& domain : {track, interval}) {
    const std::string where = domain.periodic
                                  ? fmt::format("closed track, L = {:.3f} m", domain.length)
                                  : fmt::format("interval [0, {:.3f}] m", domain.length);
    ContractReport report;
    try {
      auto kernel = entry->factory(defaults, domain);
      report = check_kernel_contract(*kernel);
      if (domain.periodic) on_track = std::move(kernel);
    } catch (const std::exception& e) {
      report.checks.push_back({"construction", false, false,
                               fmt::format("the default kernel cannot be built: {}", e.what())});
    }
    out.contract.emplace_back(where, std::move(report));
  }
  // The dimensions beyond 1 the kernel is defined on: a box and a torus in d = 2 and 3. A
  // kernel that is one-dimensional says so when it is built there, and is not checked there.
  for (int d = 2; d <= Domain::max_dimension; ++d) {
    for (const bool periodic : {false, true}) {
      Domain domain{2.0, periodic};
      domain.dimension = d;
      domain.width = 1.5;
      domain.height = 1.0;
      std::unique_ptr<AnyKernel> kernel;
      try {
        kernel = entry->factory(defaults, domain);
      } catch (const std::exception& e) {
        out.not_defined_on.push_back(fmt::format("{}: {}", domain.describe(), e.what()));
        continue;
      }
      out.contract.emplace_back(fmt::format("{} of d = {}", periodic ? "torus" : "box", d) +
                                    " " + domain.describe(),
                                check_kernel_contract(*kernel));
    }
  }
  if (!on_track) {
    out.theory.push_back({"theory", false, false, "not checked: no kernel on the closed track"});
    return out;
  }
  const auto props = on_track->properties();
  out.declared = describe_properties(props);
  out.theory.push_back(strict_definiteness_check(*on_track));
  try {
    out.theory.push_back(rate_check(*entry, props, on_track->domain()));
  } catch (const std::exception& e) {
    out.theory.push_back({"power-function rate", false, false, e.what()});
  }
  return out;
}

PluginVerification verify_plugin(const std::filesystem::path& file) {
  PluginVerification out;
  out.plugin = load_plugin(file);
  for (const auto& name : out.plugin.registered.at(std::string(kernel_kind_name))) out.kernels.push_back(verify_kernel(name));
  return out;
}

std::string format_verification(const PluginVerification& v) {
  std::string out = fmt::format(
      "plugin {}\n  module '{}', plugin ABI {}, built against rkhs-study {}\n  built for {}\n",
      v.plugin.file.string(), v.plugin.name, v.plugin.abi_version, v.plugin.rkhs_study_version,
      v.plugin.build_configuration);
  auto names = [](const std::vector<std::string>& list) {
    std::string s;
    for (std::size_t i = 0; i < list.size(); ++i) s += (i ? ", " : "") + list[i];
    return s;
  };
  const auto& registered = v.plugin.registered;
  if (const auto& kernels = registered.at(std::string(kernel_kind_name)); !kernels.empty())
    out += "  kernels: " + names(kernels) + "\n";
  if (const auto& centres = registered.at(std::string(centres_kind_name)); !centres.empty())
    out += "  centre placements (no contract, not verified): " + names(centres) + "\n";
  if (const auto& targets = registered.at(std::string(target_kind_name)); !targets.empty())
    out += "  targets (no contract, not verified): " + names(targets) + "\n";
  std::size_t checks = 0, skipped = 0, failed = 0;
  auto count = [&](const ContractCheck& c) {
    ++checks;
    if (c.skipped) ++skipped;
    if (!c.passed) ++failed;
  };
  for (const auto& k : v.kernels) {
    out += fmt::format("\nkernel '{}' with its defaults ({})\n", k.kernel,
                       k.parameters.empty() ? "no parameters" : k.parameters);
    if (!k.declared.empty()) out += "  declared: " + k.declared + "\n";
    for (const auto& [where, report] : k.contract) {
      out += "  contract on the " + where + "\n";
      for (const auto& c : report.checks) {
        out += format_check(c);
        count(c);
      }
    }
    for (const auto& why : k.not_defined_on) out += "  not defined on " + why + "\n";
    out += "  theory (closed track)\n";
    for (const auto& c : k.theory) {
      out += format_check(c);
      count(c);
    }
  }
  out +=
      fmt::format("\nverify-plugin: {} ({} checks: {} passed, {} skipped, {} failed)\n",
                  v.passed() ? "PASS" : "FAIL", checks, checks - skipped - failed, skipped, failed);
  return out;
}

}  // namespace rkhs
