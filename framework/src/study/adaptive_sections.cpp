// The sections of a study file that the adaptive study kind owns (docs/study-files.md,
// "Adaptive studies"): [adaptive], and the plugin axes [[plant]], [[law]], [[integrator]], with
// what they must agree on (study_file_parts.hpp, StudyFileSections).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/adaptive/lyapunov.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/adaptive/state_dependent.hpp"
#include "study_file_parts.hpp"

namespace rkhs::detail {

namespace {

// One lap count of [adaptive] laps: a finite number > 0, or "limit" (+infinity).
double parse_lap_count(const Reporter& report, const toml::node& node, bool in_list) {
  const auto allowed = in_list ? "a lap count > 0 or \"limit\" (the periodic steady state)"
                               : "a lap count > 0, \"limit\" (the periodic steady state) or an "
                                 "array of them";
  if (const auto* text = node.as_string()) {
    if (text->get() != "limit")
      report.fail(node.source(), "adaptive.laps",
                  fmt::format("found \"{}\", expected {}", text->get(), allowed));
    return std::numeric_limits<double>::infinity();
  }
  if (!node.is_number())
    report.fail(node.source(), "adaptive.laps",
                fmt::format("found {} ({}), expected {}", describe(node), show(node), allowed));
  const double laps = *real_of(node);
  if (!(laps > 0) || !std::isfinite(laps))
    report.fail(node.source(), "adaptive.laps",
                fmt::format("must be a finite number > 0 or \"limit\", found {}", show(node)));
  return laps;
}

struct AdaptiveSection {
  AdaptiveSettings settings;
  std::vector<double> laps_values;  // the laps axis; empty for one value
  PluginChoice reference;           // [adaptive] reference; empty name: none
};

// reference = { integrator = "radau5", rtol = 1e-11, atol = 1e-10 }: an integrator and its
// parameters (one value each, resolved against the integrator's declared parameters; those
// left out take the integrator's defaults, rtol and atol the reference's: 1e-11 and 1e-10).
PluginChoice parse_reference(const Reporter& report, const toml::node& node) {
  constexpr const char* key = "adaptive.reference";
  const auto* table = node.as_table();
  if (!table)
    report.fail(node.source(), key,
                fmt::format("expected an inline table {{ integrator = \"radau5\", rtol = 1e-11, "
                            "atol = 1e-10 }}, found {} ({})",
                            describe(node), show(node)));
  const auto* name_node = table->get("integrator");
  if (!name_node)
    report.fail(table->source(), key,
                fmt::format("missing 'integrator': the reference integrator's name (known: {})",
                            fmt::join(integrator_registry().names(), ", ")));
  if (!name_node->is_string())
    report.fail(name_node->source(), "adaptive.reference.integrator",
                fmt::format("expected an integrator name, found {} ({})", describe(*name_node),
                            show(*name_node)));
  const std::string name = name_node->as_string()->get();
  const auto* plugin = integrator_registry().find(name);
  if (!plugin)
    report.fail(name_node->source(), "adaptive.reference.integrator",
                fmt::format("unknown integrator '{}' {}", name,
                            with_suggestion(name, integrator_registry().names())));
  const auto& specs = plugin->info.parameters;
  std::vector<std::string> known;
  for (const auto& spec : specs) known.push_back(spec.name);
  std::map<std::string, ParameterValue> given;
  std::map<std::string, toml::source_region> where;
  for (auto&& [k, value] : *table) {
    const std::string parameter(k.str());
    if (parameter == "integrator") continue;
    const std::string qualified = std::string(key) + "." + parameter;
    if (std::find(known.begin(), known.end(), parameter) == known.end())
      report.fail(k.source(), qualified,
                  fmt::format("unknown parameter of integrator '{}' {}", name,
                              known.empty() ? std::string("(it has none)")
                                            : with_suggestion(parameter, known)));
    auto scalar = scalar_value(value);
    if (!scalar)
      report.fail(value.source(), qualified,
                  fmt::format("expected one value (a reference is not an axis), found {}",
                              describe(value)));
    given[parameter] = std::move(*scalar);
    where[parameter] = value.source();
  }
  // The reference's own defaults where the integrator declares rtol and atol.
  for (const auto& [parameter, fallback] : {std::pair<const char*, double>{"rtol", 1e-11},
                                            std::pair<const char*, double>{"atol", 1e-10}})
    if (std::find(known.begin(), known.end(), parameter) != known.end() &&
        !given.contains(parameter))
      given[parameter] = ParameterValue(fallback);
  try {
    return PluginChoice{name, ParameterSet::resolve(specs, given), {}};
  } catch (const ParameterError& e) {
    const auto found = where.find(e.parameter());
    report.fail(found != where.end() ? found->second : table->source(),
                std::string(key) + "." + e.parameter(), e.what());
  }
}

// path = { from = a, to = b }: a shuttle back and forth between a and b (a lap is one round
// trip); absent: laps around the track.
void read_path(const Reporter& report, const toml::table& table, double track_length,
               AdaptiveSettings& settings) {
  if (const auto* path = table.get("path")) {
    const auto* range = path->as_table();
    if (!range)
      report.fail(path->source(), "adaptive.path",
                  fmt::format("expected {{ from = ..., to = ... }} (a shuttle between two points "
                              "of the track), found {}",
                              show(*path)));
    check_keys(report, *range, "adaptive.path.", {"from", "to"});
    for (const char* key : {"from", "to"})
      if (!range->contains(key))
        report.fail(path->source(), fmt::format("adaptive.path.{}", key),
                    "missing: a shuttle path needs both ends, { from = ..., to = ... }");
    const double from = get_number(report, *range, "from", "adaptive.path.", 0, -1e-300);
    const double to = get_number(report, *range, "to", "adaptive.path.", 0, 0);
    if (!(to > from) || to > track_length * (1 + 1e-12))
      report.fail(range->get("to")->source(), "adaptive.path.to",
                  fmt::format("found {}, expected a point after from = {} and at most the track's "
                              "length {}",
                              format_real(to), format_real(from), format_real(track_length)));
    settings.shuttle_from = from;
    settings.shuttle_length = std::min(to, track_length) - from;
  }
}

// laps = 10 | "limit" | [10, 100, "limit"] (a list is an axis of the grid): the lap counts with
// where each is given, sorted; settings.laps (NaN for an axis, whose values go to
// section.laps_values). Needs settings.engine.
std::vector<std::pair<double, const toml::node*>> read_lap_counts(const Reporter& report,
                                                                  const toml::table& table,
                                                                  AdaptiveSection& section) {
  AdaptiveSettings& settings = section.settings;
  const auto* laps_node = table.get("laps");
  std::vector<std::pair<double, const toml::node*>> lap_counts;
  if (!laps_node) {
    lap_counts.emplace_back(settings.laps, nullptr);
  } else if (const auto* array = laps_node->as_array()) {
    if (array->empty())
      report.fail(laps_node->source(), "adaptive.laps", "empty list of lap counts");
    for (const auto& item : *array)
      lap_counts.emplace_back(parse_lap_count(report, item, true), &item);
    std::stable_sort(lap_counts.begin(), lap_counts.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    for (std::size_t i = 1; i < lap_counts.size(); ++i)
      if (lap_counts[i].first == lap_counts[i - 1].first)
        report.fail(lap_counts[i].second->source(), "adaptive.laps",
                    fmt::format("{} is listed twice; lap counts must be distinct",
                                laps_text(lap_counts[i].first)));
  } else {
    lap_counts.emplace_back(parse_lap_count(report, *laps_node, false), laps_node);
  }
  if (laps_node && table.contains("final_time")) {
    const auto limit = std::find_if(lap_counts.begin(), lap_counts.end(),
                                    [](const auto& c) { return std::isinf(c.first); });
    if (limit != lap_counts.end())
      report.fail(limit->second->source(), "adaptive.laps",
                  fmt::format("found \"limit\" together with final_time = {}: the periodic "
                              "limit has no final time; give laps = \"limit\" without "
                              "final_time, or a final time without laps",
                              show(*table.get("final_time"))));
    report.fail(table.source(), "adaptive", "give 'laps' or 'final_time', not both");
  }
  for (const auto& [laps, node] : lap_counts) {
    if (std::isinf(laps) && settings.engine == AdaptiveEngine::time_stepping)
      report.fail(node->source(), "adaptive.laps",
                  "found \"limit\" with engine = \"time_stepping\", which cannot step through "
                  "infinitely many laps; \"limit\" needs engine = \"automatic\" or \"lap_map\"");
    if (std::isfinite(laps) && laps != std::floor(laps) &&
        settings.engine == AdaptiveEngine::lap_map)
      report.fail(node->source(), "adaptive.laps",
                  fmt::format("found {} with engine = \"lap_map\", which advances whole laps; "
                              "give a whole number of laps, or engine = \"automatic\" or "
                              "\"time_stepping\"",
                              show(*node)));
  }
  if (laps_node && laps_node->is_array()) {
    settings.laps = std::numeric_limits<double>::quiet_NaN();  // per trial (AdaptiveTrialAxes)
    for (const auto& [laps, node] : lap_counts) section.laps_values.push_back(laps);
  } else {
    settings.laps = lap_counts.front().first;
  }
  return lap_counts;
}

// snapshot_laps: each within the longest finite run, the laps (the largest finite value of a
// laps axis) or final_time. A "limit" trial records every snapshot lap; a shorter trial of a
// laps axis the ones it reaches (trial_adaptive_settings).
void read_snapshot_laps(const Reporter& report, const toml::table& table, double track_length,
                        const std::vector<std::pair<double, const toml::node*>>& lap_counts,
                        AdaptiveSettings& settings) {
  std::optional<double> last_lap;
  std::string last_lap_text;
  if (settings.final_time > 0) {
    last_lap = settings.final_time / settings.lap_time(track_length);
    last_lap_text = fmt::format("final_time = {} s, {} laps", format_real(settings.final_time),
                                format_real(*last_lap));
  } else {
    for (const auto& [laps, node] : lap_counts)
      if (std::isfinite(laps)) {
        last_lap = laps;
        last_lap_text = fmt::format("laps = {}{}", laps_text(laps),
                                    lap_counts.size() > 1 ? ", the largest finite lap count" : "");
      }
  }
  if (const auto* laps = table.get("snapshot_laps")) {
    const auto* array = laps->as_array();
    if (!array)
      report.fail(laps->source(), "adaptive.snapshot_laps",
                  fmt::format("expected an array of lap numbers, found {}", describe(*laps)));
    for (const auto& item : *array) {
      const auto lap_number = real_of(item);
      if (!lap_number || *lap_number < 0)
        report.fail(item.source(), "adaptive.snapshot_laps",
                    fmt::format("expected a lap number >= 0, found {}", show(item)));
      const double lap = *lap_number;
      if (last_lap && lap > *last_lap * (1 + 1e-12))
        report.fail(item.source(), "adaptive.snapshot_laps",
                    fmt::format("found {}, after the end of the run ({}); snapshot laps must be "
                                "<= {}",
                                show(item), last_lap_text, format_real(*last_lap)));
      settings.snapshot_laps.push_back(lap);
    }
  }
}

// `track_length` is the domain's length (a final time in laps, for snapshot_laps).
AdaptiveSection parse_adaptive(const Reporter& report, const toml::table& root,
                               double track_length) {
  AdaptiveSection section;
  AdaptiveSettings& settings = section.settings;
  const auto* table = optional_table(report, root, "adaptive");
  if (!table)
    report.fail({}, "adaptive",
                "missing [adaptive] table (speed = ..., laps = ... or final_time = ...)");
  check_keys(report, *table, "adaptive.",
             {"speed", "laps", "final_time", "q", "road", "snapshot_laps", "snapshot_points",
              "samples_per_lap", "engine", "lap_map_rtol", "lap_map_atol", "reference", "path"});
  settings.speed = get_number(report, *table, "speed", "adaptive.", 1.0, 0);

  read_path(report, *table, track_length, settings);

  const std::vector<std::string> engines{"automatic", "lap_map", "time_stepping"};
  const auto engine = get_string(report, *table, "engine", "adaptive.", std::string("automatic"));
  if (const auto found = adaptive_engine_from_name(engine))
    settings.engine = *found;
  else
    report.fail(table->get("engine")->source(), "adaptive.engine",
                fmt::format("unknown engine \"{}\" {}", engine, with_suggestion(engine, engines)));
  settings.lap_map_rtol =
      get_number(report, *table, "lap_map_rtol", "adaptive.", settings.lap_map_rtol, 0);
  settings.lap_map_atol =
      get_number(report, *table, "lap_map_atol", "adaptive.", settings.lap_map_atol, 0);

  const auto lap_counts = read_lap_counts(report, *table, section);
  // Absent: 0 (the laps decide); given: a time > 0 (final_time = 0 ran the default laps).
  settings.final_time = get_number(report, *table, "final_time", "adaptive.", 0, 0);

  // The reference integrates every trial once more by time stepping: never with the lap map.
  if (const auto* reference = table->get("reference")) {
    section.reference = parse_reference(report, *reference);
    if (settings.engine == AdaptiveEngine::lap_map)
      report.fail(table->get("engine")->source(), "adaptive.engine",
                  "found \"lap_map\" with a reference: integration_error compares time stepping "
                  "with time stepping; use engine = \"automatic\" or \"time_stepping\" (a study "
                  "with a reference steps through time), or remove reference");
    for (const auto& [laps, node] : lap_counts)
      if (std::isinf(laps))
        report.fail(node->source(), "adaptive.laps",
                    "found \"limit\" with a reference, which integrates by time stepping and "
                    "cannot reach the periodic limit; give a number of laps or remove reference");
  }

  try {
    settings.q = WeightMatrix::parse(
        get_string(report, *table, "q", "adaptive.", std::string("identity")));
  } catch (const std::exception& e) {
    report.fail(table->get("q")->source(), "adaptive.q", e.what());
  }
  const auto road = get_string(report, *table, "road", "adaptive.", std::string("target"));
  if (road != "target" && road != "projection")
    report.fail(table->get("road")->source(), "adaptive.road",
                fmt::format("found \"{}\", expected \"target\" (f) or \"projection\" (Pi_n f, "
                            "a road in H_n)",
                            road));
  settings.projected_road = road == "projection";

  read_snapshot_laps(report, *table, track_length, lap_counts, settings);
  auto count = [&](std::string_view key, std::size_t fallback) {
    return static_cast<std::size_t>(
        get_whole_number(report, *table, key, "adaptive.", fallback, 1, 10000000));
  };
  settings.snapshot_points = count("snapshot_points", 0);
  settings.samples_per_lap = count("samples_per_lap", settings.samples_per_lap);
  return section;
}

class AdaptiveFileSections final : public StudyFileSections {
 public:
  void add_grid_factors(const toml::table& root, std::vector<GridFactor>& factors) const override {
    factors.push_back(count_plugin_axis(root, "plant", "plant", "plants"));
    factors.push_back(count_plugin_axis(root, "law", "learning law", "learning laws"));
    factors.push_back(count_plugin_axis(root, "integrator", "integrator", "integrators"));
    const auto* adaptive = root.get("adaptive");
    const auto* laps =
        adaptive && adaptive->as_table() ? adaptive->as_table()->get("laps") : nullptr;
    if (laps && laps->as_array() && laps->as_array()->size() > 1) {
      const auto count = laps->as_array()->size();
      factors.push_back(
          {fmt::format("{} values of laps", count), count, count, laps->source(), "adaptive.laps"});
    }
  }

  void read(const Reporter& report, const toml::table& root, StudyDefinition& study,
            std::vector<PluginAxis>& axes) const override {
    axes.push_back(read_plugins(report, root, "plant", catalogue_of(plant_registry()),
                                std::string("quarter_car")));
    axes.push_back(
        read_plugins(report, root, "law", catalogue_of(law_registry()), std::string("rkhs")));
    axes.push_back(read_plugins(report, root, "integrator", catalogue_of(integrator_registry()),
                                std::string("rosenbrock4")));
    auto adaptive = parse_adaptive(report, root, study.domain.length);
    auto& own = study.adaptive_axes();
    own.settings = std::move(adaptive.settings);
    own.laps_values = std::move(adaptive.laps_values);
    own.reference = std::move(adaptive.reference);
    if (own.settings.snapshot_points == 0) own.settings.snapshot_points = study.evaluation_points;
  }

  std::vector<std::vector<PluginChoice>*> axis_members(StudyDefinition& study) const override {
    auto& own = study.adaptive_axes();
    return {&own.plants, &own.laws, &own.integrators};
  }

  void check(const Reporter& report, const toml::table& root, StudyDefinition& study,
             const std::vector<PluginAxis>& kind_axes) const override {
    const PluginAxis& plant_axis = kind_axes.at(0);
    const PluginAxis& law_axis = kind_axes.at(1);
    const auto& own = study.adaptive_axes();
    // Theorem 4.1 trials: the law is the infinite-dimensional estimator, the road is f.
    if (!study.projections.empty()) {
      const auto* node = root.get("projection");
      check_instances(report, root, law_axis, [&](const PluginChoice& c, const PluginEntry&) {
        const auto law = law_registry().find(c.name)->factory(c.parameters);
        if (law->coordinates() != LawCoordinates::features)
          throw std::invalid_argument(fmt::format(
              "with [[projection]] an adaptive study compares each projection's finite estimator "
              "with the infinite-dimensional one, which the law must be: found law '{}', expected "
              "\"rkhs_embedding\" (see docs/theorems.md)",
              c.label()));
      });
      if (own.settings.projected_road)
        report.fail(node->source(), "projection",
                    "with [[projection]] the road must be the target f (adaptive.road = "
                    "\"target\"): Theorem 4.1 compares two estimators of f");
      if (own.settings.limit() || std::any_of(own.laps_values.begin(), own.laps_values.end(),
                                              [](double laps) { return std::isinf(laps); }))
        report.fail(node->source(), "projection",
                    "with [[projection]] the gaps are taken along the integration: laps = "
                    "\"limit\" has none");
    }
    check_instances(report, root, plant_axis, [&](const PluginChoice& c, const PluginEntry&) {
      const auto plant = plant_registry().find(c.name)->factory(c.parameters);
      const auto d = plant->A().rows();
      const auto Q = own.settings.q.for_dimension(d, "adaptive.q");
      solve_lyapunov(plant->A(), Q);
      const int dimension = study.domain.dimension;
      if (!plant->state_dependent() && dimension > 1)
        throw std::invalid_argument(fmt::format(
            "it drives f along a track (d = 1), and the domain has d = {}: a domain of d > 1 "
            "needs a plant whose f is a function of a read-out of {} coordinates of its state",
            dimension, dimension));
      if (plant->state_dependent()) {
        // f of the plant's state: a nonlinear system stepped through time on an interval or circle.
        AdaptiveSettings settings = own.settings;
        if (std::any_of(own.laps_values.begin(), own.laps_values.end(),
                        [](double laps) { return std::isinf(laps); }))
          settings.laps = std::numeric_limits<double>::infinity();
        if (const auto error = state_dependent_settings_error(settings, plant->period());
            !error.empty())
          throw std::invalid_argument(error);
        if (plant->readout().rows() != dimension)
          throw std::invalid_argument(fmt::format(
              "its read-out y = C x + y0 has {} coordinate{}, and f is a function on the domain of "
              "d = {}: they must agree",
              plant->readout().rows(), plant->readout().rows() == 1 ? "" : "s", dimension));
        if (dimension > 1 && !own.settings.snapshot_laps.empty())
          throw std::invalid_argument(
              "adaptive.snapshot_laps records profiles of the estimate along a domain of d = 1; "
              "remove it in d > 1");
        for (const auto& law_entry : law_axis.entries)
          for_each_combination(law_entry, [&](const std::vector<std::size_t>& at) {
            const auto law_choice = resolve_choice(report, "law", law_entry, at);
            const auto law = law_registry().find(law_choice.name)->factory(law_choice.parameters);
            if (law->coordinates() != LawCoordinates::centres)
              throw std::invalid_argument(fmt::format(
                  "law '{}' learns in feature coordinates; a state-dependent plant learns in the "
                  "span of the centres' sections (laws gradient and rkhs)",
                  law_choice.label()));
          });
      }
    });
  }
};

}  // namespace

const StudyFileSections& adaptive_file_sections() {
  static const AdaptiveFileSections sections;
  return sections;
}

}  // namespace rkhs::detail
