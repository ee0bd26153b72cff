#include "rkhs/core/registry.hpp"

#include <algorithm>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/approx/centres.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/plugin/builtins.hpp"
#include "rkhs/approx/target.hpp"

namespace rkhs {

// Registries are function-local statics: constructed on first use, whatever the order in which
// the registrars of different translation units run.
KernelRegistry& kernel_registry() {
  static KernelRegistry registry("kernel");
  return registry;
}

CentreRegistry& centre_registry() {
  static CentreRegistry registry("centres");
  return registry;
}

TargetRegistry& target_registry() {
  static TargetRegistry registry("target");
  return registry;
}

std::unique_ptr<AnyKernel> make_kernel(std::string_view name, const ParameterSet& parameters,
                                       const Domain& domain) {
  const auto* entry = kernel_registry().find(name);
  if (!entry) throw std::invalid_argument("unknown kernel '" + std::string(name) + "'");
  return entry->factory(parameters, domain);
}

std::size_t edit_distance(std::string_view a, std::string_view b) {
  // Optimal string alignment: insertions, deletions, substitutions and adjacent transpositions.
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i)
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

std::string closest_name(std::string_view name, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_distance = std::string::npos;
  for (const auto& candidate : candidates) {
    const auto d = edit_distance(name, candidate);
    if (d < best_distance) {
      best_distance = d;
      best = candidate;
    }
  }
  // Likely a misspelling: at most a third of the longer name differs (and at least one edit
  // is always allowed).
  const std::size_t allowed = std::max<std::size_t>(1, std::max(name.size(), best.size()) / 3);
  return best_distance <= allowed ? best : std::string{};
}

std::vector<std::string> registration_errors() {
  std::vector<std::string> all;
  for (auto errors : {kernel_registry().errors(), centre_registry().errors(),
                      target_registry().errors(), plant_registry().errors(),
                      law_registry().errors(), integrator_registry().errors()})
    all.insert(all.end(), errors.begin(), errors.end());
  return all;
}

const BuiltinNames& builtin_plugin_names() {
  static const BuiltinNames names{
      .kernels = {"bspline", "gaussian", "matern", "wendland"},
      .centres = {"random", "uniform"},
      .targets = {"csv", "iso8608", "sine"},
      .plants = {"linear", "quarter_car"},
      .laws = {"gradient", "rkhs"},
      .integrators = {"dopri5", "rk4", "rk_fehlberg78", "rodas4", "rosenbrock4"},
  };
  return names;
}

std::vector<std::string> missing_builtin_plugins() {
  std::vector<std::string> missing;
  const auto& builtin = builtin_plugin_names();
  for (const auto& name : builtin.kernels)
    if (!kernel_registry().find(name)) missing.push_back("kernel '" + name + "'");
  for (const auto& name : builtin.centres)
    if (!centre_registry().find(name)) missing.push_back("centres '" + name + "'");
  for (const auto& name : builtin.targets)
    if (!target_registry().find(name)) missing.push_back("target '" + name + "'");
  for (const auto& name : builtin.plants)
    if (!plant_registry().find(name)) missing.push_back("plant '" + name + "'");
  for (const auto& name : builtin.laws)
    if (!law_registry().find(name)) missing.push_back("law '" + name + "'");
  for (const auto& name : builtin.integrators)
    if (!integrator_registry().find(name)) missing.push_back("integrator '" + name + "'");
  return missing;
}

void freeze_registries() {
  kernel_registry().freeze();
  centre_registry().freeze();
  target_registry().freeze();
  plant_registry().freeze();
  law_registry().freeze();
  integrator_registry().freeze();
}

}  // namespace rkhs
