#include "rkhs/run/trial_identity.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <boost/pfr.hpp>
#include <map>
#include <stdexcept>
#include <type_traits>
#include <typeinfo>
#include <utility>
#include <variant>

#include "rkhs/approx/target.hpp"
#include "rkhs/core/build_info.hpp"
#include "rkhs/core/sha256.hpp"
#include "rkhs/plugin/plugin_loader.hpp"

namespace rkhs {

namespace {

template <class T>
struct is_vector : std::false_type {};
template <class T, class A>
struct is_vector<std::vector<T, A>> : std::true_type {};

template <class T>
struct is_variant : std::false_type {};
template <class... T>
struct is_variant<std::variant<T...>> : std::true_type {};

template <class T>
ExcludedField exclusion(const T& field, const char* name, const char* reason) {
  return {&field, &typeid(T), name, reason};
}

// Whether `field` is one of `excluded` (by address and type: a struct's first field shares its
// address).
template <class T>
bool is_excluded(const T& field, const std::vector<ExcludedField>& excluded) {
  for (const auto& e : excluded)
    if (e.address == static_cast<const void*>(&field) && *e.type == typeid(T)) return true;
  return false;
}

// Writes `value` canonically to `out`, leaving out the fields of nested aggregates that are
// `excluded`. Returns false for a type it cannot write.
template <class T>
bool write_value(const T& value, std::string& out, const std::vector<ExcludedField>& excluded) {
  if constexpr (std::is_same_v<T, std::string>) {
    out += '"';
    for (char c : value) {
      if (c == '"' || c == '\\') out += '\\';
      out += c;
    }
    out += '"';
    return true;
  } else if constexpr (std::is_same_v<T, bool>) {
    out += value ? "true" : "false";
    return true;
  } else if constexpr (std::is_floating_point_v<T>) {
    out += format_real(static_cast<double>(value));
    return true;
  } else if constexpr (std::is_integral_v<T>) {
    out += std::to_string(value);
    return true;
  } else if constexpr (std::is_same_v<T, WeightMatrix>) {
    return write_value(value.text(), out, excluded);  // as written, as when q was a string
  } else if constexpr (std::is_same_v<T, AdaptiveEngine>) {
    out += adaptive_engine_name(value);
    return true;
  } else if constexpr (std::is_enum_v<T>) {
    out += std::to_string(static_cast<long long>(value));
    return true;
  } else if constexpr (std::is_same_v<T, PluginChoice>) {
    out += value.label();
    return true;
  } else if constexpr (is_vector<T>::value) {
    out += '[';
    for (std::size_t i = 0; i < value.size(); ++i) {
      if (i) out += ',';
      if (!write_value(value[i], out, excluded)) return false;
    }
    out += ']';
    return true;
  } else if constexpr (is_variant<T>::value) {
    // A kind's own part: the alternative (the kind), then its fields.
    out += std::to_string(value.index()) + ':';
    return std::visit(
        [&](const auto& alternative) { return write_value(alternative, out, excluded); }, value);
  } else if constexpr (std::is_aggregate_v<T>) {
    bool ok = true, first = true;
    out += '{';
    boost::pfr::for_each_field(value, [&](const auto& field, std::size_t i) {
      if (is_excluded(field, excluded)) return;
      if (!first) out += ' ';
      first = false;
      out += std::to_string(i) + '=';
      ok = ok && write_value(field, out, excluded);
    });
    out += '}';
    return ok;
  } else {
    return false;
  }
}

}  // namespace

std::vector<ExcludedField> not_in_identity(const StudyDefinition& study) {
  std::vector<ExcludedField> out{
      exclusion(study.name, "name", "a label: renaming a study keeps its results"),
      exclusion(study.description, "description", "a label"),
      exclusion(study.source, "source", "where the file was read from, not what it says"),
      exclusion(study.n_values, "n_values", "each trial's n is in its key"),
      exclusion(study.tier_n_values, "tier_n_values",
                "which values of n a tier runs; each trial's n is in its key"),
      exclusion(study.kernels, "kernels", "each trial's kernel and its parameters are in its key"),
      exclusion(study.targets, "targets", "each trial's target is in its key"),
      exclusion(study.centres, "centres", "each trial's centre placement is in its key"),
      exclusion(study.projections, "projections", "each trial's projection is in its key"),
      exclusion(study.metrics, "metrics",
                "which metrics are written and fitted; what trials compute of them enters as "
                "computed_metrics()"),
      exclusion(study.abscissa, "abscissa",
                "what rates are fitted against, after the trials; what trials compute for it "
                "enters as computed_metrics()"),
      exclusion(study.rates_window, "rates_window",
                "which points rates are fitted on, after the trials"),
      exclusion(study.constant_within, "constant_within",
                "which series are reported as constant, after the trials"),
      exclusion(study.expectations, "expectations",
                "judged after the trials; what trials compute for them enters as "
                "computed_metrics()"),
      exclusion(study.warnings, "warnings", "messages about the file"),
      exclusion(study.plot, "plot", "how the figures look ([plot]), drawn after the trials"),
  };
  if (const auto* adaptive = study.adaptive_axes_if())
    out.insert(
        out.end(),
        {exclusion(adaptive->laps_values, "laps_values", "each trial's lap count is in its key"),
         exclusion(adaptive->plants, "plants", "each trial's plant is in its key"),
         exclusion(adaptive->laws, "laws", "each trial's learning law is in its key"),
         exclusion(adaptive->integrators, "integrators", "each trial's integrator is in its key")});
  return out;
}

std::string study_settings_text(const StudyDefinition& study) {
  const auto excluded = not_in_identity(study);
  std::string out;
  boost::pfr::for_each_field(study, [&](const auto& field, std::size_t i) {
    if (is_excluded(field, excluded)) return;
    if (!out.empty()) out += ' ';
    out += std::to_string(i) + '=';
    if (!write_value(field, out, excluded))
      throw std::logic_error(fmt::format(
          "trial identity: field {} of StudyDefinition has a type the identity cannot write; "
          "teach write_value() in trial_identity.cpp, or list it in not_in_identity() with why "
          "it cannot change a result",
          i));
  });
  return out;
}

namespace {

// " | modules=kernel:imq=<sha256>,..." for the trial's plugins that a loaded module registered,
// in the order of TrialSpec's fields; "" when every one is built in: the identity of a trial of
// built-in plugins only has no module part.
std::string plugin_modules_text(
    const TrialSpec& trial,
    const std::map<std::pair<std::string, std::string>, std::string>& module_of) {
  if (module_of.empty()) return {};
  std::string text;
  for (const auto& [kind, choice] : trial.plugin_choices()) {
    if (choice->name.empty()) continue;
    auto it = module_of.find({kind, choice->name});
    if (it == module_of.end()) continue;
    text += fmt::format("{}{}:{}={}", text.empty() ? " | modules=" : ",", kind, choice->name,
                        it->second);
  }
  return text;
}

}  // namespace

std::vector<std::string> trial_hashes(const StudyDefinition& study,
                                      const std::vector<TrialSpec>& trials) {
  const auto& build = build_info();
  // The metrics a trial computes are part of what it is: a record of fewer metrics cannot
  // serve a study that asks for more.
  const std::string common =
      fmt::format("rkhs-study {} {} | {} | computes {}", build.version, build.git_commit,
                  study_settings_text(study), fmt::join(study.computed_metric_names(), ","));
  std::map<std::string, std::string> data_of_target;  // target label -> data provenance
  // The module each loaded plugin came from, by (kind, name): its content hash, taken once when
  // it was loaded. Built-in plugins are in none (the build's commit covers them).
  std::map<std::pair<std::string, std::string>, std::string> module_of;
  for (const auto& module : loaded_plugins())
    for (const auto& [kind, names] : module.registered)
      for (const auto& name : names) module_of[{kind, name}] = module.sha256;
  std::vector<std::string> out;
  out.reserve(trials.size());
  for (const auto& trial : trials) {
    const auto label = trial.target.label();
    auto it = data_of_target.find(label);
    if (it == data_of_target.end()) {
      std::string provenance;
      try {
        const auto target = target_registry().find(trial.target.name)->factory(
            trial.target.parameters, study.domain);
        provenance = target->data_provenance();
      } catch (const std::exception& e) {
        provenance = std::string("unavailable: ") + e.what();
      }
      it = data_of_target.emplace(label, provenance).first;
    }
    out.push_back(sha256_hex(common + " | " + trial.key + " | data=" + it->second +
                             plugin_modules_text(trial, module_of)));
  }
  return out;
}

}  // namespace rkhs
