#include "expectation_parser.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

#include "reference_values.hpp"
#include "rkhs/approx/projection.hpp"
#include "rkhs/core/registry.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/rates/theory.hpp"
#include "rkhs/study/trial_grid.hpp"
#include "toml_reader.hpp"

namespace rkhs::detail {
namespace {

// "approximation": the kinds of study whose metrics have a theory rate, for messages.
std::string theory_kind_names() {
  std::string names;
  for (const auto* kind : study_kind_table())
    if (kind->has_theory()) names += (names.empty() ? "" : ", ") + std::string(kind->name());
  return names;
}

bool valid_tier_name(const std::string& name) {
  return !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
  });
}

// Reads one [[expect]] table; `columns` are the study's axis columns (the selector keys).
class ExpectationReader {
 public:
  ExpectationReader(const StudyDefinition& study, const std::vector<std::string>& columns)
      : study_(study), columns_(columns) {}

  Expectation read(const toml::table& table, std::size_t number) const {
    Expectation e;
    e.number = number;
    e.location = fmt::format("{}:{}:{}", study_.source, table.source().begin.line,
                             table.source().begin.column);
    check_keys(table);
    read_metric(table, e);
    if (const auto* node = table.get("name")) e.name = string_at(*node, "expect.name");
    if (const auto* node = table.get("tier")) e.tiers = parse_tiers(*node, study_.source, "expect.tier");
    if (const auto* node = table.get("xfail")) e.xfail = read_xfail(*node);
    read_selectors(table, e);
    read_kind(table, e);
    e.window = read_fit_window(Reporter(study_.source), table, "expect.", study_);
    if (e.kind == ExpectationKind::bound && (e.window.h_from || e.window.h_to))
      fail(study_.source, table.get(e.window.h_from ? "h_from" : "h_to")->source(),
           e.window.h_from ? "expect.h_from" : "expect.h_to",
           "a bound holds at each n: select its n with n_from, n_to or last");
    return e;
  }

 private:
  static inline const std::vector<std::string> reserved_{
      "metric", "name",     "tier",      "xfail",  "theory", "rate",   "tolerance", "model",
      "bound",  "constant", "reference", "n_from", "n_to",   "h_from", "h_to",      "last"};

  // xfail = "reason": why the expectation is known not to hold, which reports repeat.
  std::string read_xfail(const toml::node& node) const {
    if (!node.is_string() || node.as_string()->get().find_first_not_of(" \t") == std::string::npos)
      fail(study_.source, node.source(), "expect.xfail",
           fmt::format("expected the reason the expectation is known not to hold (a non-empty "
                       "string, e.g. xfail = \"the floor sets in before n = 50\"), found {}",
                       show(node)));
    return node.as_string()->get();
  }

  std::string string_at(const toml::node& node, std::string_view key) const {
    if (!node.is_string())
      fail(study_.source, node.source(), key, fmt::format("expected a string, found {}", show(node)));
    return node.as_string()->get();
  }

  double number_at(const toml::node& node, std::string_view key) const {
    const auto value = real_of(node);
    if (!value || !std::isfinite(*value))
      fail(study_.source, node.source(), key, fmt::format("expected a finite number, found {}", show(node)));
    return *value;
  }

  // A metric the study measures, for `metric`, `bound.by` and `bound.times`.
  std::string metric_at(const toml::node& node, std::string_view key) const {
    const auto metric = string_at(node, key);
    if (std::find(study_.metrics.begin(), study_.metrics.end(), metric) == study_.metrics.end()) {
      const auto& all = study_.all_metrics();
      if (std::find(all.begin(), all.end(), metric) != all.end())
        fail(study_.source, node.source(), key,
             fmt::format("metric '{}' is not measured by this study (study.metrics: {})", metric,
                         fmt::join(study_.metrics, ", ")));
      fail(study_.source, node.source(), key,
           fmt::format("unknown metric '{}' {}", metric, with_suggestion(metric, study_.metrics)));
    }
    return metric;
  }

  void check_keys(const toml::table& table) const {
    auto allowed = reserved_;
    allowed.insert(allowed.end(), columns_.begin(), columns_.end());
    for (auto&& [key, value] : table) {
      const std::string name(key.str());
      if (std::find(allowed.begin(), allowed.end(), name) == allowed.end())
        fail(study_.source, key.source(), "expect." + name,
             fmt::format("unknown key (an expectation takes {}, and this study's axis columns "
                         "as group selectors: {}{})",
                         fmt::join(reserved_, ", "), fmt::join(columns_, ", "),
                         closest_name(name, allowed).empty()
                             ? std::string()
                             : fmt::format("; did you mean '{}'?", closest_name(name, allowed))));
    }
  }

  void read_metric(const toml::table& table, Expectation& e) const {
    const auto* node = table.get("metric");
    if (!node)
      fail(study_.source, table.source(), "expect.metric",
           fmt::format("missing: which metric is expected to behave (one of: {})", fmt::join(study_.metrics, ", ")));
    e.metric = metric_at(*node, "expect.metric");
  }

  void read_selectors(const toml::table& table, Expectation& e) const {
    for (const auto& column : columns_) {  // in column order, so selector_text reads naturally
      const auto* node = table.get(column);
      if (!node) continue;
      AxisSelector selector{column, {}};
      auto add = [&](const toml::node& item) {
        auto value = scalar_value(item);
        if (!value)
          fail(study_.source, item.source(), "expect." + column,
               fmt::format("expected a value or a list of values, found {}", show(item)));
        selector.values.push_back(std::move(*value));
      };
      if (const auto* array = node->as_array()) {
        if (array->empty()) fail(study_.source, node->source(), "expect." + column, "empty list of values");
        for (const auto& item : *array) add(item);
      } else {
        add(*node);
      }
      e.selectors.push_back(std::move(selector));
    }
  }

  void read_kind(const toml::table& table, Expectation& e) const {
    const auto& src = study_.source;
    const auto* theory = table.get("theory");
    const auto* rate = table.get("rate");
    const auto* model = table.get("model");
    const auto* bound = table.get("bound");
    const auto* constant = table.get("constant");
    const auto* reference = table.get("reference");
    const auto* tolerance = table.get("tolerance");
    if (theory && !(theory->is_boolean() && theory->as_boolean()->get())) {
      if (!theory->is_boolean())
        fail(src, theory->source(), "expect.theory", fmt::format("expected true, found {}", show(*theory)));
      theory = nullptr;  // theory = false: as if absent
    }
    const int what = (theory ? 1 : 0) + (rate ? 1 : 0) + (bound ? 1 : 0) + (constant ? 1 : 0) +
                     (reference ? 1 : 0);
    if (what > 1)
      fail(src, table.source(), "expect",
           "give one of theory = true, rate = ..., bound = { ... }, constant = ... or reference "
           "= { ... } per [[expect]] table");
    if (what == 0 && !model)
      fail(src, table.source(), "expect",
           "say what is expected: theory = true, rate = -1.5 (or { min = ..., max = ... }), "
           "model = \"exponential\", bound = { by = \"...\" }, constant = { value = 1, "
           "within = 1e-12 }, or reference = { file = \"...\", value = \"...\", within = 0.05 }");
    if (model) {
      const auto name = string_at(*model, "expect.model");
      if (name == "power_law") e.model = RateModel::power_law;
      else if (name == "exponential") e.model = RateModel::exponential;
      else
        fail(src, model->source(), "expect.model",
             fmt::format("found \"{}\", expected \"power_law\" (log-log) or \"exponential\" "
                         "(log-linear in n)", name));
      if (theory || bound || constant || reference)
        fail(src, model->source(), "expect.model",
             theory  ? "theory = true chooses the model from the kernel's metadata: remove 'model'"
             : bound ? "a bound has no rate model: remove 'model'"
             : reference ? "reference values have no rate model: remove 'model'"
                         : "a constant has no rate model: remove 'model'");
    }
    if (tolerance) {
      e.tolerance = number_at(*tolerance, "expect.tolerance");
      if (!(e.tolerance > 0))
        fail(src, tolerance->source(), "expect.tolerance",
             fmt::format("must be > 0, found {}", show(*tolerance)));
      const bool derived = rate && rate->as_table() && rate->as_table()->contains("at_least");
      if (!theory && !(rate && rate->is_number()) && !derived)
        fail(src, tolerance->source(), "expect.tolerance",
             "only for theory = true, rate = <number> or rate = { at_least = \"metric\" } (an "
             "interval { min, max } or a bound has no tolerance)");
    }

    if (theory) {
      e.kind = ExpectationKind::theory;
      if (!study_.kind_descriptor().has_theory())
        fail(src, theory->source(), "expect.theory",
             fmt::format("theory rates are known for {} studies only (this study is "
                         "kind = \"{}\")",
                         theory_kind_names(), study_kind_name(study_.kind())));
    } else if (rate) {
      e.kind = ExpectationKind::rate;
      read_rate(*rate, tolerance != nullptr, e);
    } else if (bound) {
      e.kind = ExpectationKind::bound;
      read_bound(*bound, e);
    } else if (constant) {
      e.kind = ExpectationKind::constant;
      read_constant(*constant, e);
    } else if (reference) {
      e.kind = ExpectationKind::reference;
      read_reference(*reference, e);
    } else {
      e.kind = ExpectationKind::model;
    }
  }

  void read_rate(const toml::node& rate, bool has_tolerance, Expectation& e) const {
    const auto& src = study_.source;
    if (rate.is_number()) {
      e.expected = number_at(rate, "expect.rate");
      if (e.model == RateModel::exponential && !has_tolerance)
        fail(src, rate.source(), "expect.rate",
             "an exponential rate (per unit of n) has no natural scale: give tolerance = ...");
      e.interval = {*e.expected - e.tolerance, *e.expected + e.tolerance};
      return;
    }
    const auto* interval = rate.as_table();
    if (!interval)
      fail(src, rate.source(), "expect.rate",
           fmt::format("expected a number or {{ min = ..., max = ... }}, found {}", show(rate)));
    for (auto&& [key, value] : *interval)
      if (key.str() != "min" && key.str() != "max" && key.str() != "at_least")
        fail(src, key.source(), fmt::format("expect.rate.{}", key.str()),
             "unknown key (known: min, max, at_least)");
    if (const auto* reference = interval->get("at_least")) {
      if (interval->contains("min") || interval->contains("max"))
        fail(src, rate.source(), "expect.rate",
             "at_least derives the interval from another metric's rate: give it alone, without "
             "min or max");
      if (e.model != RateModel::power_law)
        fail(src, rate.source(), "expect.rate.at_least",
             "compares power-law rates: remove 'model'");
      e.rate_reference = metric_at(*reference, "expect.rate.at_least");
      if (e.rate_reference == e.metric)
        fail(src, reference->source(), "expect.rate.at_least",
             fmt::format("'{}' is the expectation's own metric: name another one", e.metric));
      (void)has_tolerance;  // e.tolerance (default 0.1) is the slack on the reference's rate
      return;
    }
    if (const auto* low = interval->get("min")) e.interval.low = number_at(*low, "expect.rate.min");
    if (const auto* high = interval->get("max")) e.interval.high = number_at(*high, "expect.rate.max");
    if (!interval->contains("min") && !interval->contains("max"))
      fail(src, rate.source(), "expect.rate", "give min, max or both");
    if (e.interval.low > e.interval.high)
      fail(src, rate.source(), "expect.rate",
           fmt::format("min ({}) is above max ({})", format_real(e.interval.low),
                       format_real(e.interval.high)));
  }

  // constant = true, or constant = { value = 1, within = 1e-12 } (within optional, >= 0).
  void read_constant(const toml::node& node, Expectation& e) const {
    const auto& src = study_.source;
    if (const auto* flag = node.as_boolean()) {
      if (!flag->get())
        fail(src, node.source(), "expect.constant",
             "constant = false expects nothing: to expect a rate, write rate = ...");
      return;
    }
    const auto* table = node.as_table();
    if (!table)
      fail(src, node.source(), "expect.constant",
           fmt::format("expected true or {{ value = 1, within = 1e-12 }}, found {}", show(node)));
    for (auto&& [key, value] : *table)
      if (key.str() != "value" && key.str() != "within")
        fail(src, key.source(), fmt::format("expect.constant.{}", key.str()),
             "unknown key (known: value, within)");
    const auto* value = table->get("value");
    if (!value)
      fail(src, node.source(), "expect.constant.value",
           "missing: the value the series is expected to keep (or write constant = true for any "
           "value)");
    e.constant.value = number_at(*value, "expect.constant.value");
    if (const auto* within = table->get("within")) {
      e.constant.within = number_at(*within, "expect.constant.within");
      if (!(e.constant.within >= 0))
        fail(src, within->source(), "expect.constant.within",
             fmt::format("must be >= 0 (an absolute band about value), found {}", show(*within)));
    }
  }

  // reference = { file = "paper/table1.csv", value = "condition_number", where = { kernel =
  // "bspline_first_order" }, within = 0.05 }; the file is read here, so its errors are found
  // with the study file's.
  void read_reference(const toml::node& node, Expectation& e) const {
    const auto& src = study_.source;
    const auto* table = node.as_table();
    if (!table)
      fail(src, node.source(), "expect.reference",
           fmt::format("expected {{ file = \"paper/table1.csv\", value = \"column\", where = {{ "
                       "column = \"...\" }}, within = 0.05 }}, found {}",
                       show(node)));
    for (auto&& [key, value] : *table)
      if (key.str() != "file" && key.str() != "value" && key.str() != "where" &&
          key.str() != "within")
        fail(src, key.source(), fmt::format("expect.reference.{}", key.str()),
             "unknown key (known: file, value, where, within)");
    auto& spec = e.reference;
    for (const auto* key : {"file", "value", "within"})
      if (!table->contains(key))
        fail(src, node.source(), fmt::format("expect.reference.{}", key),
             std::string_view(key) == "file"    ? "missing: the CSV file of the published values, "
                                                  "relative to the data root"
             : std::string_view(key) == "value" ? "missing: the column of the published values"
                                                : "missing: the relative tolerance of the ratio "
                                                  "metric / reference about 1 (e.g. 0.05)");
    spec.file = string_at(*table->get("file"), "expect.reference.file");
    spec.value_column = string_at(*table->get("value"), "expect.reference.value");
    spec.within = number_at(*table->get("within"), "expect.reference.within");
    if (!(spec.within >= 0))
      fail(src, table->get("within")->source(), "expect.reference.within",
           fmt::format("must be >= 0 (relative: |metric / reference - 1| <= within), found {}",
                       show(*table->get("within"))));
    if (const auto* where = table->get("where")) {
      const auto* selectors = where->as_table();
      if (!selectors)
        fail(src, where->source(), "expect.reference.where",
             fmt::format("expected a table of column = value, found {}", show(*where)));
      for (auto&& [key, value] : *selectors) {
        const auto scalar = scalar_value(value);
        if (!scalar)
          fail(src, value.source(), fmt::format("expect.reference.where.{}", key.str()),
               fmt::format("expected a string or a number, found {}", show(value)));
        spec.where.emplace_back(std::string(key.str()), format_value(*scalar));
      }
    }
    try {
      read_reference_values(spec);
    } catch (const std::invalid_argument& error) {
      fail(src, table->get("file")->source(), "expect.reference.file", error.what());
    }
  }

  void read_bound(const toml::node& node, Expectation& e) const {
    const auto& src = study_.source;
    const auto* table = node.as_table();
    if (!table)
      fail(src, node.source(), "expect.bound",
           fmt::format("expected {{ by = \"metric\", times = \"metric\", constant = 1.0 }}, found {}",
                       show(node)));
    for (auto&& [key, value] : *table)
      if (key.str() != "by" && key.str() != "times" && key.str() != "constant" &&
          key.str() != "at_least")
        fail(src, key.source(), fmt::format("expect.bound.{}", key.str()),
             "unknown key (known: by, times, constant, at_least)");
    const auto* by = table->get("by");
    if (!by && table->contains("times"))
      fail(src, node.source(), "expect.bound.by", "missing: 'times' multiplies 'by'");
    if (!by && !table->contains("constant"))
      fail(src, node.source(), "expect.bound",
           "give by = \"metric\" (metric <= constant * by [* times]) or constant = ... "
           "(metric <= constant)");
    if (by) e.bound.by = metric_at(*by, "expect.bound.by");
    if (const auto* times = table->get("times")) e.bound.times = metric_at(*times, "expect.bound.times");
    if (const auto* constant = table->get("constant")) {
      e.bound.constant = number_at(*constant, "expect.bound.constant");
      if (!(e.bound.constant > 0))
        fail(src, constant->source(), "expect.bound.constant",
             fmt::format("must be > 0, found {}", show(*constant)));
    }
    if (const auto* at_least = table->get("at_least")) {
      e.bound.at_least = number_at(*at_least, "expect.bound.at_least");
      if (!(*e.bound.at_least >= 0 && *e.bound.at_least < e.bound.constant))
        fail(src, at_least->source(), "expect.bound.at_least",
             fmt::format("must be >= 0 and below constant = {}, found {}",
                         format_real(e.bound.constant), show(*at_least)));
    }
  }

  // Every expectation must select a group of `groups_` (one trial per group of the study); a
  // theory expectation must have a theory there.
 public:
  void check_selection(const toml::table& table, const Expectation& e,
                       const std::vector<TrialSpec>& groups_) const {
    std::vector<const TrialSpec*> selected;
    for (const auto& group : groups_)
      if (e.selects(group)) selected.push_back(&group);
    if (selected.empty()) {
      std::vector<std::string> available;
      for (const auto& selector : e.selectors) {
        std::set<std::string> values;
        for (const auto& group : groups_)
          if (auto v = axis_values({selector.column}, group).front(); !v.empty()) values.insert(v);
        available.push_back(fmt::format("{}: {}", selector.column,
                                        fmt::join(std::vector<std::string>(values.begin(), values.end()), ", ")));
      }
      fail(study_.source, table.source(), "expect",
           fmt::format("{} selects no group of this study (values in the study: {})",
                       e.selector_text(), fmt::join(available, "; ")));
    }
    // Each value of a list must select something too: `degree = [1, 5]` where no group has
    // degree 5 is a typo, not a wish.
    for (std::size_t k = 0; k < e.selectors.size(); ++k) {
      const auto& selector = e.selectors[k];
      if (selector.values.size() < 2) continue;
      const auto* array = table.get(selector.column)->as_array();
      for (std::size_t v = 0; v < selector.values.size(); ++v) {
        Expectation single = e;
        single.selectors[k].values = {selector.values[v]};
        if (std::any_of(groups_.begin(), groups_.end(),
                        [&](const TrialSpec& group) { return single.selects(group); }))
          continue;
        std::set<std::string> values;
        for (const auto* group : selected)
          if (auto value = axis_values({selector.column}, *group).front(); !value.empty())
            values.insert(value);
        fail(study_.source, array ? array->get(v)->source() : table.source(), "expect." + selector.column,
             fmt::format("{} selects no group of this study{} (the groups it selects have {}: {})",
                         single.selector_text(),
                         e.selectors.size() > 1 ? " together with the other selectors" : "",
                         selector.column,
                         fmt::join(std::vector<std::string>(values.begin(), values.end()), ", ")));
      }
    }
    if (e.kind == ExpectationKind::reference) {
      // Every n of the reference must be an n of the study: a value nobody measures is a typo
      // or another grid, not something to leave unjudged.
      const auto& spec = e.reference;
      const auto& ns = study_.n_values;
      for (std::size_t k = 0; k < spec.n.size(); ++k)
        if (std::find(ns.begin(), ns.end(), spec.n[k]) == ns.end())
          fail(study_.source, table.get("reference")->source(), "expect.reference",
               fmt::format("{} (line {}) gives n = {}, which this study does not run (n: {})",
                           spec.file, spec.lines[k], spec.n[k], fmt::join(ns, ", ")));
    }
    if (e.kind != ExpectationKind::theory) return;
    const auto* row = study_.kind_descriptor().find_metric(e.metric);
    for (const auto* group : selected) {
      if (row && row->theory != TheoryLaw::level_reduction && scales_kernel(group->projection))
        fail(study_.source, table.get("theory")->source(), "expect.theory",
             fmt::format("projection '{}' scales its kernel with the level (rho_j = nu h_j), so "
                         "the theory of a fixed kernel for {} does not describe it; its theory "
                         "is Wendland's multiscale theorem, judged on level_reduction_factor "
                         "(theory = true there), or declare a rate",
                         group->projection.name, e.metric));
      std::string why;
      if (!theory_rate(e.metric,
                       kernel_properties(group->kernel.name, group->kernel.parameters, study_.domain),
                       &why))
        fail(study_.source, table.get("theory")->source(), "expect.theory",
             fmt::format("kernel {}: {}", group->kernel.label(), why));
    }
  }

  // Whether `projection` scales its kernel with the level (ProjectionProperties::
  // kernel_scaled_with_level); false when it cannot be built (reported with its entry).
  static bool scales_kernel(const PluginChoice& projection) {
    if (projection.name.empty()) return false;
    try {
      return projection_registry()
          .find(projection.name)
          ->factory(projection.parameters)
          ->properties()
          .kernel_scaled_with_level;
    } catch (const std::exception&) {
      return false;
    }
  }

  const StudyDefinition& study_;
  const std::vector<std::string>& columns_;
};

// Trials in which every choice of every plugin axis appears, in the order of the axis (the
// others at their last choice once theirs run out): as many trials as the longest axis, with
// the axis columns of the whole grid.
std::vector<TrialSpec> one_trial_per_choice(const StudyDefinition& study) {
  const auto axes = study.plugin_axes();  // in the order of TrialSpec::plugin_choices()
  std::size_t count = 1;
  for (const auto& axis : axes) count = std::max(count, axis.second->size());
  const auto* adaptive = study.adaptive_axes_if();
  std::vector<TrialSpec> out(count);
  for (std::size_t i = 0; i < count; ++i) {
    out[i].kind_axes = trial_kind_axes(study.kind());
    const auto choices = out[i].plugin_choices();
    for (std::size_t a = 0; a < axes.size(); ++a)
      if (const auto& options = *axes[a].second; !options.empty())
        *choices[a].second = options[std::min(i, options.size() - 1)];
    if (adaptive && !adaptive->laps_values.empty())
      out[i].adaptive_axes().laps = adaptive->laps_values.front();
    out[i].n = study.n_values.empty() ? 0 : study.n_values.front();
  }
  return out;
}

}  // namespace

std::vector<std::string> parse_tiers(const toml::node& node, const std::string& source,
                                     std::string_view key) {
  std::vector<std::string> tiers;
  auto add = [&](const toml::node& item) {
    if (!item.is_string() || !valid_tier_name(item.as_string()->get()))
      fail(source, item.source(), key,
           fmt::format("expected a tier name (letters, digits, '_', '-'), found {}", show(item)));
    tiers.push_back(item.as_string()->get());
  };
  if (const auto* array = node.as_array()) {
    if (array->empty()) fail(source, node.source(), key, "empty list of tiers");
    for (const auto& item : *array) add(item);
  } else {
    add(node);
  }
  return tiers;
}

namespace {

// The [[expect]] tables of `root` (none when it has none).
std::vector<const toml::table*> expect_tables(const toml::table& root,
                                              const StudyDefinition& study) {
  const auto* node = root.get("expect");
  if (!node) return {};
  std::vector<const toml::table*> tables;
  if (const auto* array = node->as_array()) {
    for (const auto& item : *array) {
      if (!item.is_table())
        fail(study.source, item.source(), "expect",
             fmt::format("expected a table ([[expect]]), found {}", show(item)));
      tables.push_back(item.as_table());
    }
  } else if (node->is_table()) {
    tables.push_back(node->as_table());
  } else {
    fail(study.source, node->source(), "expect",
         fmt::format("expected [[expect]] tables, found {}", show(*node)));
  }
  return tables;
}

}  // namespace

std::vector<Expectation> read_expectations(const toml::table& root,
                                           const StudyDefinition& outline) {
  const auto tables = expect_tables(root, outline);
  if (tables.empty()) return {};
  const auto columns = axis_columns(one_trial_per_choice(outline));
  const ExpectationReader reader(outline, columns);
  std::vector<Expectation> out;
  for (std::size_t i = 0; i < tables.size(); ++i) out.push_back(reader.read(*tables[i], i + 1));
  return out;
}

void check_expectation_selections(const toml::table& root, const StudyDefinition& study,
                                  const std::vector<Expectation>& expectations) {
  const auto tables = expect_tables(root, study);
  if (tables.empty()) return;
  const auto columns = axis_columns(one_trial_per_choice(study));
  const ExpectationReader reader(study, columns);
  // One representative trial per group (the selectors look at axes, which a group shares):
  // the trials of the grid with its first n only, so the grid is not expanded again.
  StudyDefinition one_n = study;
  // (erase, not resize: GCC 12 warns about resize's growing path, which cannot run here)
  if (one_n.n_values.size() > 1)
    one_n.n_values.erase(one_n.n_values.begin() + 1, one_n.n_values.end());
  const auto groups = one_n.trials();
  for (std::size_t i = 0; i < tables.size(); ++i)
    reader.check_selection(*tables[i], expectations.at(i), groups);
}

}  // namespace rkhs::detail
