// Trial identity (rkhs/run/trial_identity.hpp): every field of the study definition, changed in
// turn, changes the identity unless it is one of the fields declared unable to change a result,
// which must then leave it unchanged.
#include <boost/pfr.hpp>
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <type_traits>
#include <typeinfo>
#include <variant>
#include <vector>

#include "rkhs/run/run.hpp"
#include "rkhs/run/trial_identity.hpp"

namespace {

using namespace rkhs;

template <class T>
struct is_vector : std::false_type {};
template <class T, class A>
struct is_vector<std::vector<T, A>> : std::true_type {};
template <class T>
struct is_map : std::false_type {};
template <class K, class V, class C, class A>
struct is_map<std::map<K, V, C, A>> : std::true_type {};
template <class T>
struct is_optional : std::false_type {};
template <class T>
struct is_optional<std::optional<T>> : std::true_type {};
template <class T>
struct is_variant : std::false_type {};
template <class... T>
struct is_variant<std::variant<T...>> : std::true_type {};

// A different value of the same type.
template <class T>
void perturb(T& value) {
  if constexpr (std::is_same_v<T, std::string>) {
    value += "x";
  } else if constexpr (std::is_same_v<T, bool>) {
    value = !value;
  } else if constexpr (std::is_floating_point_v<T>) {
    value = value * 2 + 1;
  } else if constexpr (std::is_integral_v<T>) {
    value = value + 1;
  } else if constexpr (std::is_enum_v<T>) {
    value = static_cast<T>(static_cast<std::underlying_type_t<T>>(value) + 1);
  } else if constexpr (is_vector<T>::value) {
    value.emplace_back();
  } else if constexpr (is_map<T>::value) {
    value.emplace(typename T::key_type{"x"}, typename T::mapped_type{});
  } else if constexpr (is_optional<T>::value) {
    if (value) value.reset();
    else value.emplace();
  } else if constexpr (std::is_same_v<T, WeightMatrix>) {
    value = WeightMatrix::parse(value.text() == "identity" ? "diag(2, 3)" : "identity");
  } else {
    static_assert(std::is_same_v<T, PluginChoice>, "teach perturb() this field type");
    value.name += "x";
  }
}

template <class T>
constexpr bool is_leaf =
    std::is_same_v<T, std::string> || std::is_arithmetic_v<T> || std::is_enum_v<T> ||
    is_vector<T>::value || is_map<T>::value || is_optional<T>::value ||
    std::is_same_v<T, PluginChoice> || !std::is_aggregate_v<T>;

// The metrics of a result, bit for bit (NaN equal to NaN).
bool same_metrics(const TrialResult& a, const TrialResult& b) {
  if (a.ok != b.ok || a.metrics.size() != b.metrics.size()) return false;
  for (std::size_t i = 0; i < a.metrics.size(); ++i)
    if (!(a.metrics[i] == b.metrics[i] || (std::isnan(a.metrics[i]) && std::isnan(b.metrics[i]))))
      return false;
  return true;
}

// The exclusion `field` is (by address and type: a struct's first field shares its address).
template <class T>
const ExcludedField* exclusion_of(const T& field, const std::vector<ExcludedField>& excluded) {
  for (const auto& e : excluded)
    if (e.address == static_cast<const void*>(&field) && *e.type == typeid(T)) return &e;
  return nullptr;
}

// Calls check(path, exclusion) once per leaf of `value` (nested aggregates are walked field by
// field; a variant, a kind's own part, is switched to another alternative, then its own
// alternative's fields are walked), with that leaf changed; the leaf is restored afterwards.
// `exclusion`: the field of not_in_identity() the leaf is in, or nullptr.
template <class T, class Check>
void each_leaf_changed(T& value, const std::string& path,
                       const std::vector<ExcludedField>& excluded, const ExcludedField* exclusion,
                       const Check& check) {
  if (!exclusion) exclusion = exclusion_of(value, excluded);
  if constexpr (is_variant<T>::value) {
    const T saved = value;
    if (value.index() == 0)
      value.template emplace<1>();
    else
      value.template emplace<0>();
    check(path + ".kind", exclusion);
    value = saved;
    std::visit(
        [&](auto& alternative) {
          each_leaf_changed(alternative, path + "." + std::to_string(value.index()), excluded,
                            exclusion, check);
        },
        value);
  } else if constexpr (is_leaf<T>) {
    const T saved = value;
    perturb(value);
    check(path, exclusion);
    value = saved;
  } else {
    boost::pfr::for_each_field(value, [&](auto& field, std::size_t i) {
      each_leaf_changed(field, path + "." + std::to_string(i), excluded, exclusion, check);
    });
  }
}

const char* adaptive_study = R"(
[study]
name = "identity"
kind = "adaptive"
evaluation_points = 64
[domain]
radius = 1.0
[grid]
n = [4, 6]
[[kernel]]
name = "gaussian"
[[target]]
name = "sine"
[[plant]]
name = "linear"
A = "-1"
B = "1"
[[law]]
name = "gradient"
[[integrator]]
name = "rosenbrock4"
[adaptive]
speed = 0.5
laps = 1
snapshot_laps = [1]
)";

}  // namespace

TEST_CASE("every study setting that can change a result changes the trial identity",
          "[store][identity]") {
  const auto study = parse_study(adaptive_study, "identity.toml");
  const auto trials = study.trials();
  const auto base_text = study_settings_text(study);
  const auto base_hashes = trial_hashes(study, trials);
  const auto base_result = run_trial(study, trials.front(), {});
  REQUIRE(base_result.ok);

  auto changed = study;
  const auto excluded = not_in_identity(changed);
  std::set<std::string> excluded_seen;
  std::size_t included_leaves = 0;
  boost::pfr::for_each_field(changed, [&](auto& field, std::size_t i) {
    each_leaf_changed(
        field, std::to_string(i), excluded, nullptr,
        [&](const std::string& path, const ExcludedField* exclusion) {
          const auto text = study_settings_text(changed);
          if (exclusion) {
            INFO("StudyDefinition field " << exclusion->name << " (" << path
                                          << "): " << exclusion->reason);
            CHECK(text == base_text);
            // The claim that it cannot change a result, checked: the trial computes the same.
            CHECK(same_metrics(run_trial(changed, trials.front(), {}), base_result));
            excluded_seen.insert(exclusion->name);
          } else {
            INFO("StudyDefinition field " << path << " changed, identity text: " << text);
            CHECK(text != base_text);
            CHECK(trial_hashes(changed, trials) != base_hashes);
            ++included_leaves;
          }
        });
  });
  // Every exclusion names a field of the study definition (none is stale).
  CHECK(excluded_seen.size() == excluded.size());
  // kind, domain (2), evaluation points, solver (2), limits (2), the adaptive settings (11: with
  // engine, lap_map_rtol and lap_map_atol) at least.
  CHECK(included_leaves >= 19);
  // The engine is written by its name.
  CHECK_THAT(base_text, Catch::Contains("automatic"));
  changed.adaptive_axes().settings.engine = AdaptiveEngine::time_stepping;
  CHECK_THAT(study_settings_text(changed), Catch::Contains("time_stepping"));
}

TEST_CASE("the trial identity is the same for the same study and differs between trials",
          "[store][identity]") {
  const auto a = parse_study(adaptive_study, "identity.toml");
  const auto b = parse_study(adaptive_study, "elsewhere/renamed.toml");
  const auto ha = trial_hashes(a, a.trials());
  CHECK(ha == trial_hashes(b, b.trials()));  // the source file is not part of it
  REQUIRE(ha.size() == 2);
  CHECK(ha[0] != ha[1]);  // n is in the key
}

TEST_CASE("a laps axis: each lap count is its own trial identity, and adding one keeps the others",
          "[store][identity][laps]") {
  auto with_laps = [](const std::string& laps) {
    std::string text = adaptive_study;
    text.replace(text.find("laps = 1\nsnapshot_laps = [1]"), 28, laps);
    return parse_study(text, "identity.toml");
  };
  const auto two = with_laps("laps = [1, 2]");
  const auto three = with_laps("laps = [1, 2, \"limit\"]");
  const auto h2 = trial_hashes(two, two.trials());
  const auto h3 = trial_hashes(three, three.trials());
  REQUIRE(h2.size() == 4);  // laps 1, 2 x n 4, 6
  REQUIRE(h3.size() == 6);
  CHECK(std::set<std::string>(h2.begin(), h2.end()).size() == 4);
  // The trials both studies have keep their identity: their stored results are reused.
  CHECK(std::vector<std::string>(h3.begin(), h3.begin() + 4) == h2);
  // One lap count is a setting, not an axis: a different identity from the axis's trial.
  CHECK(trial_hashes(with_laps("laps = 2"), with_laps("laps = 2").trials()).front() != h2[2]);
}

TEST_CASE("an approximation trial computes only its study's metrics, and that is its identity",
          "[store][identity][work]") {
  const std::string head = R"(
[study]
name = "selected"
kind = "approximation"
evaluation_points = 512
)";
  const std::string rest = R"(
[domain]
radius = 1.0
[grid]
n = [8]
[[kernel]]
name = "gaussian"
sigma = 0.5
[[target]]
name = "sine"
[[centres]]
name = "uniform"
)";
  const auto all = parse_study(head + rest, "all.toml");
  const auto some = parse_study(head + "metrics = [\"l2_error\"]\n" + rest, "some.toml");
  const auto against_h =
      parse_study(head + "metrics = [\"l2_error\"]\nabscissa = \"h\"\n" + rest, "h.toml");
  CHECK(some.computed_metric_names() == std::vector<std::string>{"l2_error"});
  CHECK(against_h.computed_metric_names() ==
        std::vector<std::string>{"fill_distance", "l2_error"});
  CHECK(all.computed_metric_names() == all.computable_metrics());
  // A record of fewer metrics never serves a study that asks for more.
  CHECK(trial_hashes(some, some.trials()) != trial_hashes(all, all.trials()));
  CHECK(trial_hashes(some, some.trials()) != trial_hashes(against_h, against_h.trials()));

  const auto full = run_trial(all, all.trials().front(), {});
  const auto selected = run_trial(some, some.trials().front(), {});
  REQUIRE(full.ok);
  REQUIRE(selected.ok);
  const auto l2 = all.metric_index("l2_error");
  CHECK(selected.metrics[l2] == full.metrics[l2]);
  for (std::size_t i = 0; i < selected.metrics.size(); ++i)
    if (i != l2) CHECK(std::isnan(selected.metrics[i]));
}
