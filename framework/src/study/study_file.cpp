// Study files read into a StudyDefinition (docs/study-files.md): every section, its keys and
// values checked, plugin names and parameters resolved against the registries.
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <sstream>

#include "expectation_parser.hpp"
#include "rkhs/approx/approximation.hpp"
#include "rkhs/approx/centres.hpp"
#include "rkhs/approx/projection.hpp"
#include "rkhs/approx/target.hpp"
#include "rkhs/core/data_root.hpp"
#include "rkhs/core/input_file.hpp"
#include "rkhs/core/random.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/plugin/plugin_loader.hpp"
#include "rkhs/study/study.hpp"
#include "study_file_parts.hpp"
#include "toml_reader.hpp"

namespace rkhs {

using namespace detail;

namespace {

// The largest n a study may ask for (no Gram matrix is anywhere near this size), and the
// most values of n one grid may list.
constexpr std::int64_t max_n = 1'000'000'000;
constexpr std::int64_t max_n_values = 100000;
// The longest study name (docs/study-files.md): it names the output folder, and file names
// are at most 255 bytes on common file systems.
constexpr std::size_t max_study_name = 100;
// [limits] trials when the file does not give it (docs/study-files.md).
constexpr std::uint64_t default_max_trials = 1'000'000;
// The largest [limits] trials: every trial of the grid is held in memory (its plugin choices
// and keys, about 1.7 KB: 10^6 trials took 1.7 GB), and a grid the count admits must be one
// that can be built (a 2^31-trial grid under trials = 1e15 ended in std::bad_alloc).
constexpr std::uint64_t max_max_trials = 10'000'000;

// n = [10, 20] | { from = 10, to = 100, step = 10 } | { from = 8, to = 1024, factor = 2 }.
// Ranges are counted before they are expanded, without overflow: bounds above max_n and more
// than max_n_values values are errors.
std::vector<std::size_t> parse_n(const Reporter& report, const toml::node& node,
                                 const std::string& key) {
  std::vector<std::pair<std::int64_t, toml::source_region>> values;
  if (const auto* array = node.as_array()) {
    for (const auto& item : *array) {
      if (!item.is_integer())
        report.fail(item.source(), key,
                    fmt::format("expected integers, found {} ({})", describe(item), show(item)));
      values.emplace_back(item.as_integer()->get(), item.source());
    }
  } else if (const auto* range = node.as_table()) {
    check_keys(report, *range, key + ".", {"from", "to", "step", "factor"});
    auto integer = [&](std::string_view name) -> std::optional<std::int64_t> {
      const auto* v = range->get(name);
      if (!v) return std::nullopt;
      if (!v->is_integer())
        report.fail(v->source(), fmt::format("{}.{}", key, name),
                    fmt::format("expected an integer, found {} ({})", describe(*v), show(*v)));
      return v->as_integer()->get();
    };
    const auto from = integer("from"), to = integer("to"), step = integer("step"),
               factor = integer("factor");
    if (!from || !to) report.fail(range->source(), key, "a range needs 'from' and 'to'");
    if (step.has_value() == factor.has_value())
      report.fail(range->source(), key, "a range needs exactly one of 'step' or 'factor'");
    for (const char* name : {"from", "to"}) {
      const auto value = *integer(name);
      if (value < 1 || value > max_n)
        report.fail(range->get(name)->source(), fmt::format("{}.{}", key, name),
                    fmt::format("must be between 1 and {} (centres), found {}", max_n, value));
    }
    if (step && *step < 1)
      report.fail(range->get("step")->source(), key + ".step",
                  fmt::format("must be >= 1, found {}", *step));
    if (factor && *factor < 2)
      report.fail(range->get("factor")->source(), key + ".factor",
                  fmt::format("must be >= 2, found {}", *factor));
    if (*to < *from)
      report.fail(range->source(), key, fmt::format("'to' ({}) is below 'from' ({})", *to, *from));
    // 1 <= from <= to <= max_n: neither the count nor the values can overflow.
    if (step) {
      const std::int64_t count = (*to - *from) / *step + 1;
      if (count > max_n_values)
        report.fail(range->source(), key,
                    fmt::format("{} values of n (from {} to {} in steps of {}), more than {}",
                                count, *from, *to, *step, max_n_values));
      for (std::int64_t i = 0; i < count; ++i)
        values.emplace_back(*from + i * *step, range->source());
    } else {
      for (std::int64_t v = *from;; v *= *factor) {
        values.emplace_back(v, range->source());
        if (v > *to / *factor) break;  // v * factor > to, computed without overflow
      }
    }
  } else {
    report.fail(node.source(), key,
                fmt::format("expected an array of integers or a range table "
                            "{{ from, to, step | factor }}, found {} ({})",
                            describe(node), show(node)));
  }
  if (values.empty()) report.fail(node.source(), key, "no values");
  std::vector<std::size_t> n;
  for (const auto& [v, where] : values) {
    if (v < 1 || v > max_n)
      report.fail(where, key,
                  fmt::format("must be between 1 and {} (centres), found {}", max_n, v));
    n.push_back(static_cast<std::size_t>(v));
  }
  std::sort(n.begin(), n.end());
  if (std::adjacent_find(n.begin(), n.end()) != n.end())
    report.fail(node.source(), key, "values must be distinct");
  return n;
}

// Refuses a grid of more than `cap` trials before anything of it is built, at the entry or
// list that contributes most, naming the product and the lists that multiply to it.
void check_grid_size(const Reporter& report, const toml::table& root,
                     const StudyKindDescriptor& kind, std::size_t n_count, const toml::node& n_node,
                     std::uint64_t cap) {
  std::vector<GridFactor> factors{
      count_plugin_axis(root, "kernel", "kernel", "kernels"),
      count_plugin_axis(root, "target", "target", "targets"),
      count_plugin_axis(root, "centres", "centre placement", "centre placements")};
  if (root.get("projection"))
    factors.push_back(count_plugin_axis(root, "projection", "projection", "projections"));
  kind.file_sections().add_grid_factors(root, factors);
  factors.push_back({fmt::format("{} value{} of n", n_count, n_count == 1 ? "" : "s"), n_count,
                     n_count, n_node.source(), "grid.n"});
  std::uint64_t trials = 1;
  const GridFactor* largest = &factors.front();
  for (const auto& factor : factors) {
    trials = saturating_product(trials, factor.count);
    if (factor.largest > largest->largest) largest = &factor;
  }
  if (trials <= cap) return;
  std::vector<std::string> texts;
  for (const auto& factor : factors) texts.push_back(factor.text);
  report.fail(largest->where, largest->key,
              fmt::format("the grid has {} trials, more than [limits] trials = {}: {}; shorten "
                          "these lists, or raise [limits] trials",
                          trials == std::numeric_limits<std::uint64_t>::max()
                              ? std::string("more than 10^19")
                              : std::to_string(trials),
                          cap, fmt::join(texts, " x ")));
}

// Every extent of the domain (length, 2 pi radius, each of lengths) lies in
// [Domain::min_extent, Domain::max_extent]; the reason, for messages.
bool in_extent_range(double extent) {
  return extent >= Domain::min_extent && extent <= Domain::max_extent;
}
constexpr const char* extent_range_reason =
    "beyond these the squared distances, volumes and spline knots computed on the domain leave "
    "the range of double";

bool valid_study_name(const std::string& name) {
  return !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
  }) && name.front() != '.';
}

// [study]: name, description, kind, abscissa, evaluation_points; the sections of other kinds
// are refused.
const toml::table& read_header(const Reporter& report, const toml::table& root,
                               StudyDefinition& study) {
  const auto* header = optional_table(report, root, "study");
  if (!header) report.fail({}, "study", "missing [study] table (with at least name = \"...\")");
  check_keys(report, *header, "study.",
             {"name", "description", "kind", "metrics", "abscissa", "evaluation_points"});
  study.name = get_string(report, *header, "name", "study.", std::nullopt);
  if (study.name.size() > max_study_name)
    report.fail(header->get("name")->source(), "study.name",
                fmt::format("is {} characters long, at most {} are allowed (it names the output "
                            "folder results/<name>/ and the files in it)",
                            study.name.size(), max_study_name));
  if (!valid_study_name(study.name))
    report.fail(header->get("name")->source(), "study.name",
                fmt::format("'{}' is not a valid name (letters, digits, '_', '-', '.'; it names "
                            "the output folder)",
                            study.name));
  study.description = get_string(report, *header, "description", "study.", std::string{});
  const auto kind = get_string(report, *header, "kind", "study.", std::string("approximation"));
  if (const auto known = study_kind_from_name(kind))
    study.kind_axes = study_kind_axes(*known);
  else
    report.fail(header->get("kind")->source(), "study.kind",
                fmt::format("unknown study kind '{}' (known: {})", kind, study_kind_names()));
  // A section another kind owns (StudyKindDescriptor::own_sections) is refused.
  for (const auto* other : study_kind_table())
    if (other != &study.kind_descriptor())
      for (const auto section : other->own_sections())
        if (const auto* node = root.get(section))
          report.fail(
              node->source(), std::string(section),
              fmt::format("only for {0} studies: add kind = \"{0}\" to [study]", other->name()));
  const auto abscissa = get_string(report, *header, "abscissa", "study.", std::string("n"));
  if (abscissa == "n")
    study.abscissa = Abscissa::n;
  else if (abscissa == "h" || abscissa == "fill_distance")
    study.abscissa = Abscissa::fill_distance;
  else
    report.fail(header->get("abscissa")->source(), "study.abscissa",
                fmt::format("found \"{}\", expected \"n\" or \"h\" (fill distance)", abscissa));
  study.evaluation_points = static_cast<std::size_t>(
      get_whole_number(report, *header, "evaluation_points", "study.", 4096, 2, 100000000));
  return *header;
}

// [domain]: an interval, a closed track or a box or torus in R^d.
void read_domain(const Reporter& report, const toml::table& root, StudyDefinition& study) {
  const auto* domain = optional_table(report, root, "domain");
  if (!domain)
    report.fail({}, "domain",
                "missing [domain] table (length = ..., radius = ... or lengths = [...])");
  check_keys(report, *domain, "domain.", {"length", "radius", "lengths", "periodic"});
  const int given = int(domain->contains("length")) + int(domain->contains("radius")) +
                    int(domain->contains("lengths"));
  if (given != 1)
    report.fail(domain->source(), "domain",
                "give exactly one of 'length' (metres), 'radius' (a closed track of length "
                "2 pi radius) or 'lengths' (a box or torus in R^d: its extents in metres, e.g. "
                "lengths = [1.0, 1.0] for d = 2)");
  if (const auto* lengths = domain->get("lengths")) {
    const auto* list = lengths->as_array();
    if (!list || list->empty() || list->size() > std::size_t{Domain::max_dimension})
      report.fail(lengths->source(), "domain.lengths",
                  fmt::format("expected a list of 1 to {} extents in metres (one per axis), "
                              "found {}",
                              Domain::max_dimension, show(*lengths)));
    study.domain.dimension = static_cast<int>(list->size());
    for (std::size_t a = 0; a < list->size(); ++a) {
      const auto& item = *list->get(a);
      const auto value = real_of(item);
      if (!value)
        report.fail(item.source(), "domain.lengths",
                    fmt::format("axis {}: expected an extent in metres (a number between {} and "
                                "{}), found {}",
                                a + 1, format_real(Domain::min_extent),
                                format_real(Domain::max_extent), show(item)));
      if (!in_extent_range(*value))
        report.fail(item.source(), "domain.lengths",
                    fmt::format("axis {}: must be between {} and {} metres, found {} ({})", a + 1,
                                format_real(Domain::min_extent), format_real(Domain::max_extent),
                                show(item), extent_range_reason));
      (a == 0 ? study.domain.length : a == 1 ? study.domain.width : study.domain.height) = *value;
    }
  } else if (domain->contains("length")) {
    study.domain.length = real_of(*domain->get("length")).value_or(0);
    if (!in_extent_range(study.domain.length))
      report.fail(domain->get("length")->source(), "domain.length",
                  fmt::format("must be between {} and {} metres, found {} ({})",
                              format_real(Domain::min_extent), format_real(Domain::max_extent),
                              show(*domain->get("length")), extent_range_reason));
  } else {
    // The track's length 2 pi radius must lie in the extents' range.
    const double radius = real_of(*domain->get("radius")).value_or(0);
    study.domain.length = 2 * std::numbers::pi * radius;
    if (!in_extent_range(study.domain.length))
      report.fail(domain->get("radius")->source(), "domain.radius",
                  fmt::format("must be between {} and {} metres (the track's length, 2 pi "
                              "radius, between {} and {}), found {} ({})",
                              format_real(Domain::min_extent / (2 * std::numbers::pi)),
                              format_real(Domain::max_extent / (2 * std::numbers::pi)),
                              format_real(Domain::min_extent), format_real(Domain::max_extent),
                              show(*domain->get("radius")), extent_range_reason));
  }
  study.domain.periodic = get_bool(report, *domain, "periodic", "domain.", true);
  // An adaptive study in d > 1 learns f of a plant's read-out of d coordinates: every plant
  // must be state-dependent with such a read-out (checked with the plants below).
}

// [grid] n and [limits]; the grid's size is checked before anything of it is built.
const toml::node& read_grid_and_limits(const Reporter& report, const toml::table& root,
                                       StudyDefinition& study) {
  const auto* grid = optional_table(report, root, "grid");
  if (!grid || !grid->contains("n"))
    report.fail(grid ? grid->source() : toml::source_region{}, "grid.n",
                "missing: the number of centres, e.g. n = { from = 10, to = 100, step = 10 }");
  check_keys(report, *grid, "grid.", {"n", "tier_n"});
  study.n_values = parse_n(report, *grid->get("n"), "grid.n");
  if (const auto* tiers = grid->get("tier_n")) {
    const auto* table = tiers->as_table();
    if (!table || table->empty())
      report.fail(tiers->source(), "grid.tier_n",
                  fmt::format("expected a table of tiers and their values of n, e.g. tier_n = "
                              "{{ quick = [10, 20] }}, found {} ({})",
                              describe(*tiers), show(*tiers)));
    for (const auto& [tier, values] : *table) {
      const std::string key = fmt::format("grid.tier_n.{}", tier.str());
      auto n = parse_n(report, values, key);
      for (const auto v : n)
        if (!std::binary_search(study.n_values.begin(), study.n_values.end(), v))
          report.fail(values.source(), key,
                      fmt::format("n = {} is not one of grid.n (a tier runs some of them)", v));
      study.tier_n_values.emplace(std::string(tier.str()), std::move(n));
    }
  }

  std::uint64_t max_trials = default_max_trials;
  if (const auto* limits = optional_table(report, root, "limits")) {
    check_keys(report, *limits, "limits.",
               {"trial_seconds", "matrix_megabytes", "memory_megabytes", "trials"});
    study.limits.trial_seconds =
        get_number(report, *limits, "trial_seconds", "limits.", 0, -1e-300);
    study.limits.matrix_megabytes = get_number(report, *limits, "matrix_megabytes", "limits.",
                                               study.limits.matrix_megabytes, 0);
    study.limits.memory_megabytes = get_number(report, *limits, "memory_megabytes", "limits.",
                                               study.limits.memory_megabytes, 0);
    max_trials =
        get_whole_number(report, *limits, "trials", "limits.", max_trials, 1, max_max_trials,
                         " (every trial of the grid is held in memory, about 1.7 KB each)");
  }
  // Before any plugin choice or trial is built: a short file can ask for billions of trials.
  // Before any plugin choice or trial is built: a short file can ask for billions of trials.
  check_grid_size(report, root, study.kind_descriptor(), study.n_values.size(), *grid->get("n"),
                  max_trials);
  return *grid->get("n");
}

// [solver], [rates].
void read_solver_and_rates(const Reporter& report, const toml::table& root,
                           StudyDefinition& study) {
  if (const auto* solver = optional_table(report, root, "solver")) {
    check_keys(report, *solver, "solver.", {"singular", "regularisation"});
    const auto policy =
        get_string(report, *solver, "singular", "solver.", std::string("pseudo_inverse"));
    if (policy == "pseudo_inverse")
      study.solver.singular = SingularPolicy::pseudo_inverse;
    else if (policy == "regularised")
      study.solver.singular = SingularPolicy::regularised;
    else if (policy == "fail")
      study.solver.singular = SingularPolicy::fail;
    else
      report.fail(
          solver->get("singular")->source(), "solver.singular",
          fmt::format("found \"{}\", expected \"pseudo_inverse\", \"regularised\" or \"fail\"",
                      policy));
    study.solver.regularisation =
        get_number(report, *solver, "regularisation", "solver.", 0, -1e-300);
  }

  if (const auto* algebra = optional_table(report, root, "linear_algebra")) {
    check_keys(report, *algebra, "linear_algebra.", {"solver"});
    const auto solver =
        get_string(report, *algebra, "solver", "linear_algebra.", std::string("dense"));
    if (solver == "dense")
      study.solver.algebra = GramAlgebra::dense;
    else if (solver == "sparse")
      study.solver.algebra = GramAlgebra::sparse;
    else if (solver == "auto")
      study.solver.algebra = GramAlgebra::automatic;
    else
      report.fail(algebra->get("solver")->source(), "linear_algebra.solver",
                  fmt::format("found \"{}\", expected \"dense\", \"sparse\" or \"auto\"", solver));
  }

  if (const auto* rates = optional_table(report, root, "rates")) {
    auto keys = fit_window_keys;
    keys.push_back("constant_within");
    check_keys(report, *rates, "rates.", keys);
    study.rates_window = read_fit_window(report, *rates, "rates.", study);
    study.constant_within =
        get_number(report, *rates, "constant_within", "rates.", default_constant_within, -1e-300);
    if (!(study.constant_within < 1.0))
      report.fail(rates->get("constant_within")->source(), "rates.constant_within",
                  fmt::format("expected a relative band in [0, 1), found {}",
                              format_real(study.constant_within)));
  }
}

// Builds every kernel, target, placement and projection of the expanded axes once: a
// combination that is invalid only for this domain (e.g. a non-periodic sine on a closed track)
// is an input error, not a failed trial.
void check_common_instances(const Reporter& report, const toml::table& root,
                            const toml::node& n_node, StudyDefinition& study,
                            const std::vector<PluginAxis>& axes,
                            const std::optional<PluginAxis>& projections) {
  check_instances(report, root, axes[0], [&](const PluginChoice& c, const PluginEntry&) {
    kernel_registry().find(c.name)->factory(c.parameters, study.domain);
  });
  check_instances(report, root, axes[1], [&](const PluginChoice& c, const PluginEntry& entry) {
    const auto target = target_registry().find(c.name)->factory(c.parameters, study.domain);
    for (const auto& note : target->notes())
      study.warnings.push_back(report.locate(entry.where, "target", "note: " + note));
  });
  // In d > 1 every placement must place every n in this domain (a grid needs n = m^d): the n
  // it cannot place are reported at grid.n, all of them, each with the placement's reason.
  if (study.domain.dimension > 1)
    check_instances(report, root, axes[2], [&](const PluginChoice& c, const PluginEntry&) {
      const auto placement = centre_registry().find(c.name)->factory(c.parameters);
      std::vector<std::string> reasons;
      for (const auto n : study.n_values) {
        try {
          placement->place(n, study.domain, 0);
        } catch (const std::invalid_argument& e) {
          reasons.emplace_back(e.what());
        }
      }
      if (reasons.size() == 1)
        report.fail(n_node.source(), "grid.n",
                    fmt::format("centres {}: {}", c.given_label(), reasons[0]));
      if (reasons.size() > 1)
        report.fail(n_node.source(), "grid.n",
                    fmt::format("centres {}: {} values of n cannot be placed: {}", c.given_label(),
                                reasons.size(), fmt::join(reasons, "; ")));
    });
  // Every kernel with every projection and n: a projection that cannot be built for one (a
  // spline space of another kernel, an n that is not a level) is an input error.
  if (projections)
    check_instances(report, root, *projections, [&](const PluginChoice& c, const PluginEntry&) {
      const auto projection = projection_registry().find(c.name)->factory(c.parameters);
      const auto properties = projection->properties();
      for (const auto& k : study.kernels) {
        const auto kernel = kernel_registry().find(k.name)->factory(k.parameters, study.domain);
        if (!properties.requires_kernel.empty() && kernel->name() != properties.requires_kernel)
          throw std::invalid_argument(
              fmt::format("works with the {} kernel only, and the study pairs it with kernel '{}'",
                          properties.requires_kernel, k.label()));
        for (const auto n : study.n_values) {
          try {
            projection->check(*kernel, n);
          } catch (const std::invalid_argument& e) {
            throw std::invalid_argument(fmt::format("kernel '{}': {}", k.label(), e.what()));
          }
        }
      }
    });
}

}  // namespace

StudyDefinition parse_study(std::string_view text, const std::string& source_name) {
  const Reporter report(source_name);
  toml::table root;
  check_toml_nesting(report, text);
  try {
    root = toml::parse(text, source_name);
  } catch (const toml::parse_error& error) {
    report.fail(error.source(), "", fmt::format("invalid TOML: {}", error.description()));
  }
  check_keys(report, root, "",
             {"study", "domain", "grid", "kernel", "target", "centres", "projection", "solver",
              "linear_algebra", "limits", "rates", "adaptive", "plant", "law", "integrator",
              "plugins", "expect", "plot"});
  load_study_plugins(report, root);

  StudyDefinition study;
  study.source = source_name;
  const auto& header = read_header(report, root, study);
  read_domain(report, root, study);
  const auto& n_node = read_grid_and_limits(report, root, study);
  const auto& kind_sections = study.kind_descriptor().file_sections();

  // The plugin axes are read and checked here and expanded once the rest of the file is
  // checked: a mistake anywhere is found before a large grid is built. The kind's own axes
  // follow the common ones.
  std::vector<PluginAxis> axes{
      read_plugins(report, root, "kernel", catalogue_of(kernel_registry()), std::nullopt),
      read_plugins(report, root, "target", catalogue_of(target_registry()), std::string("sine")),
      read_plugins(report, root, "centres", catalogue_of(centre_registry()),
                   std::string("uniform"))};
  kind_sections.read(report, root, study, axes);
  // [[projection]]: an axis only when the file has the section (a study without one projects
  // by interpolation at the centres, and its keys say nothing about projections).
  // In an adaptive study each trial also runs the finite estimator of its projection beside the
  // law's infinite-dimensional one (Theorem 4.1, rkhs/adaptive/finite_to_infinite.hpp).
  std::optional<PluginAxis> projections;
  if (root.get("projection"))
    projections =
        read_plugins(report, root, "projection", catalogue_of(projection_registry()), std::nullopt);
  read_metrics(report, header, study,
               projections ? first_choices(report, *projections) : std::vector<PluginChoice>{});
  read_solver_and_rates(report, root, study);
  if (const auto* plot = optional_table(report, root, "plot"))
    study.plot = parse_plot(report, *plot, study);
  check_evaluation_grid(report, header, study);

  // Where each axis of `axes` goes, in the same order.
  std::vector<std::vector<PluginChoice>*> axis_members{&study.kernels, &study.targets,
                                                       &study.centres};
  for (auto* member : kind_sections.axis_members(study)) axis_members.push_back(member);
  // [[expect]] tables first against an outline of the grid (the first choice of each entry:
  // the same axis columns), then the axes expanded.
  for (std::size_t a = 0; a < axes.size(); ++a) *axis_members[a] = first_choices(report, axes[a]);
  if (projections) study.projections = first_choices(report, *projections);
  auto expectations = detail::read_expectations(root, study);
  for (std::size_t a = 0; a < axes.size(); ++a) *axis_members[a] = expand_plugins(report, axes[a]);
  if (projections) study.projections = expand_plugins(report, *projections);

  check_common_instances(report, root, n_node, study, axes, projections);
  const std::vector<PluginAxis> kind_axes(axes.begin() + 3, axes.end());
  kind_sections.check(report, root, study, kind_axes);
  detail::check_expectation_selections(root, study, expectations);
  study.expectations = std::move(expectations);
  return study;
}

StudyDefinition load_study(const std::filesystem::path& file) {
  std::string text;
  try {
    text = read_input_file(file, "study file", max_study_file_bytes);
  } catch (const InputFileError& error) {
    throw StudyError(error.what());
  }
  return parse_study(text, file.string());
}

}  // namespace rkhs
