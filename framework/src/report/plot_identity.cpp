// What tells the trials of a plot apart: their identities split into factors, the panels
// they are split into, and short legends and titles (rkhs/report/plots.cpp).
#include <fmt/format.h>

#include <algorithm>
#include <limits>
#include <map>
#include <optional>

#include "plot_parts.hpp"
#include "rkhs/core/printable.hpp"

namespace rkhs::plot_detail {

namespace {

// The lap count of a trial of a study with a laps axis.
std::optional<double> laps_of(const TrialSpec& trial) {
  const auto* adaptive = trial.adaptive_axes_if();
  return adaptive ? adaptive->laps : std::nullopt;
}

}  // namespace

// The text of `factors` of one trial: "name=value" pairs separated by commas, except that a
// plugin's own parameters follow it after a space ("kernel=bspline degree=1, class=A").
std::string identity_text(const Identity& identity, std::size_t trial,
                          const std::vector<std::size_t>& factors) {
  std::string out;
  std::string_view last_axis;
  for (auto f : factors) {
    const auto& value = identity.values[trial][f];
    if (value.empty()) continue;
    if (!out.empty())
      out += identity.owner[f] != std::string::npos && identity.axes[f] == last_axis ? " " : ", ";
    out += value;
    last_axis = identity.axes[f];
  }
  return out;
}

Identity identify(const std::vector<const TrialSpec*>& trials) {
  Identity out;
  out.values.resize(trials.size());
  std::vector<std::pair<std::string, std::size_t>> parameter_factors;  // (parameter, factor)
  auto add_factor = [&](const std::string& name, const std::string& axis, std::size_t owner) {
    out.factors.push_back(name);
    out.axes.push_back(axis);
    out.owner.push_back(owner);
    return out.factors.size() - 1;
  };
  // The plugin axes of each trial (those of its kind), in the order of trials.csv's columns.
  std::vector<std::vector<std::pair<const char*, const PluginChoice*>>> choices;
  for (const auto* trial : trials) choices.push_back(trial->plugin_choices());
  const std::size_t axis_count = choices.empty() ? 0 : choices.front().size();
  for (std::size_t a = 0; a < axis_count; ++a) {
    const auto axis = choices.front()[a].first;
    out.plugin_axes.emplace_back(axis);
    // The trial's choice of this axis.
    auto choice_of = [&](std::size_t t) -> const PluginChoice& { return *choices[t][a].second; };
    std::vector<std::string> names;
    for (std::size_t t = 0; t < trials.size(); ++t)
      if (const auto& name = choice_of(t).name;
          std::find(names.begin(), names.end(), name) == names.end())
        names.push_back(name);
    if (names.size() == 1 && names.front().empty()) continue;  // an axis the study has not
    // The parameters of each plugin of the axis, in order, with their distinct values.
    auto spread = [&](const std::string& name) {
      std::vector<std::pair<std::string, std::vector<std::string>>> parameters;
      for (std::size_t t = 0; t < trials.size(); ++t) {
        const auto& choice = choice_of(t);
        if (choice.name != name) continue;
        for (const auto& parameter_and_value : choice.parameters.values()) {
          const auto& parameter = parameter_and_value.first;
          const auto& value = parameter_and_value.second;
          auto it = std::find_if(parameters.begin(), parameters.end(),
                                 [&](const auto& p) { return p.first == parameter; });
          if (it == parameters.end()) it = parameters.insert(parameters.end(), {parameter, {}});
          if (const auto text = format_value(value);
              std::find(it->second.begin(), it->second.end(), text) == it->second.end())
            it->second.push_back(text);
        }
      }
      return parameters;
    };
    // The parameters that differ within a plugin, in order of first appearance; the others
    // are constants, of the axis (one plugin) or of their plugin.
    std::vector<std::string> differing;
    std::map<std::string, std::vector<std::string>> differing_in;
    std::string single = std::string(axis) + "=" + names.front();
    for (const auto& name : names) {
      std::string constant;
      for (const auto& [parameter, values] : spread(name)) {
        if (values.size() == 1) {
          (((names.size() == 1 ? single : constant) += ' ') += parameter) += "=" + values.front();
          continue;
        }
        differing_in[name].push_back(parameter);
        if (std::find(differing.begin(), differing.end(), parameter) == differing.end())
          differing.push_back(parameter);
      }
      if (names.size() > 1 && !constant.empty()) out.constants.push_back(name + ":" + constant);
    }
    if (names.size() == 1) out.constants.push_back(single);
    std::size_t plugin = std::string::npos;
    if (names.size() > 1) {
      plugin = add_factor(axis, axis, std::string::npos);
      for (std::size_t t = 0; t < trials.size(); ++t)
        out.values[t].push_back(std::string(axis) + "=" + choice_of(t).name);
    }
    for (const auto& parameter : differing) {
      parameter_factors.emplace_back(parameter, add_factor(parameter, axis, plugin));
      for (std::size_t t = 0; t < trials.size(); ++t) {
        const auto& choice = choice_of(t);
        std::string text;
        const auto& own = differing_in[choice.name];
        if (std::find(own.begin(), own.end(), parameter) != own.end())
          for (const auto& [name, value] : choice.parameters.values())
            if (name == parameter) text = format_value(value);
        out.values[t].push_back(text);
      }
    }
  }
  // A parameter factor is named by its parameter ("class"), or by its column of trials.csv
  // ("target_seed") when two axes share the parameter name.
  for (const auto& parameter_and_factor : parameter_factors) {
    const auto& parameter = parameter_and_factor.first;
    const auto f = parameter_and_factor.second;
    const bool shared = std::count_if(parameter_factors.begin(), parameter_factors.end(),
                                      [&](const auto& p) { return p.first == parameter; }) > 1;
    std::string name = parameter;
    if (shared && out.axes[f] != "kernel") {
      name = out.axes[f];  // (operator+ here trips GCC 12's -Wrestrict false positive)
      name += '_';
      name += parameter;
    }
    out.factors[f] = name;
    for (auto& values : out.values)
      if (!values[f].empty()) values[f] = name + "=" + values[f];
  }
  // Laps, nested just outside n.
  std::vector<std::string> laps;
  for (const auto* trial : trials)
    if (const auto count = laps_of(*trial)) {
      if (const auto text = "laps=" + laps_text(*count);
          std::find(laps.begin(), laps.end(), text) == laps.end())
        laps.push_back(text);
    }
  if (laps.size() == 1) out.constants.push_back(laps.front());
  if (laps.size() > 1) {
    add_factor("laps", "laps", std::string::npos);
    for (std::size_t t = 0; t < trials.size(); ++t)
      out.values[t].push_back("laps=" + laps_text(*laps_of(*trials[t])));
  }
  return out;
}

// The factors (indices into identity.factors) whose values split `identity`'s trials into
// panels of at most `most` each: none when all fit one plot; otherwise the set giving the
// fewest panels, then the one with fewer factors, then the one of earlier factors, a
// parameter's plugin always with it. Every set of factors is tried (up to 16 factors; beyond,
// factors are added greedily).
std::vector<std::size_t> panel_factors(const Identity& identity, std::size_t most) {
  const std::size_t k = identity.factors.size();
  if (identity.values.size() <= most || k == 0) return {};
  auto largest_panel = [&](const std::vector<std::size_t>& chosen, std::size_t* panels) {
    std::map<std::vector<std::string>, std::size_t> count;
    for (const auto& values : identity.values) {
      std::vector<std::string> key;
      for (auto f : chosen) key.push_back(values[f]);
      ++count[key];
    }
    std::size_t largest = 0;
    for (const auto& [key, n] : count) largest = std::max(largest, n);
    if (panels) *panels = count.size();
    return largest;
  };
  if (k > 16) {
    std::vector<std::size_t> chosen;
    while (largest_panel(chosen, nullptr) > most && chosen.size() < k) {
      std::size_t best = k, best_largest = std::numeric_limits<std::size_t>::max();
      for (std::size_t f = 0; f < k; ++f) {
        if (std::find(chosen.begin(), chosen.end(), f) != chosen.end()) continue;
        auto trial = chosen;
        trial.push_back(f);
        if (const auto largest = largest_panel(trial, nullptr); largest < best_largest) {
          best_largest = largest;
          best = f;
        }
      }
      chosen.push_back(best);
      if (const auto owner = identity.owner[best];
          owner != std::string::npos &&
          std::find(chosen.begin(), chosen.end(), owner) == chosen.end())
        chosen.push_back(owner);
    }
    std::sort(chosen.begin(), chosen.end());
    return chosen;
  }
  std::vector<std::size_t> best;
  std::size_t best_panels = std::numeric_limits<std::size_t>::max();
  for (std::size_t mask = 1; mask < (std::size_t{1} << k); ++mask) {
    std::vector<std::size_t> chosen;
    bool complete = true;  // a parameter with its plugin
    for (std::size_t f = 0; f < k; ++f)
      if (mask & (std::size_t{1} << f)) {
        chosen.push_back(f);
        if (const auto owner = identity.owner[f]; owner != std::string::npos)
          complete = complete && (mask & (std::size_t{1} << owner));
      }
    if (!complete) continue;
    std::size_t panels = 0;
    if (largest_panel(chosen, &panels) > most) continue;
    const bool better =
        panels < best_panels ||
        (panels == best_panels &&
         (chosen.size() < best.size() || (chosen.size() == best.size() && chosen < best)));
    if (better) {
      best = chosen;
      best_panels = panels;
    }
  }
  return best;
}

// Short legend text for a group: the plugin labels without the defaults' noise, and the lap
// count of a laps axis.
std::string legend(const TrialSpec& trial) {
  std::string out = trial.kernel.label();
  if (const auto* adaptive = trial.adaptive_axes_if()) {
    for (const auto* choice : {&adaptive->law, &adaptive->integrator})
      if (!choice->name.empty()) out += ", " + choice->name;
    if (adaptive->laps)  // a laps axis: one curve per count
      out += ", laps=" + laps_text(*adaptive->laps);
  }
  return out;
}

// The constants of `identity` that a short title names: each plugin every curve shares, by
// name ("kernel=matern", not its parameters nor an expression target's formula), a lap count,
// and which axes the curves are the same for.
std::string short_constants(const Identity& identity) {
  std::vector<std::string> names;
  for (const auto& constant : identity.constants) {
    const auto equals = constant.find('=');
    const auto axis = constant.substr(0, equals);
    const bool plugin = std::find(identity.plugin_axes.begin(), identity.plugin_axes.end(), axis) !=
                        identity.plugin_axes.end();
    if (equals != std::string::npos && (plugin || axis == "laps"))
      names.push_back(constant.substr(0, constant.find(' ')));
    else if (constant.starts_with("the same for every"))
      names.push_back(constant);
  }
  std::string out;
  for (const auto& name : names) out += (out.empty() ? "" : ", ") + name;
  return out;
}

}  // namespace rkhs::plot_detail
