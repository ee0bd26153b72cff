#pragma once
// Target functions: the unknown f the estimate approximates (a road profile in arc length).

#include <functional>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "rkhs/core/domain.hpp"
#include "rkhs/core/registry.hpp"

namespace rkhs {

/// The boundary owns nothing across it (plugin/module.hpp): values are written into the
/// caller's storage or handed to the caller's sink, never returned in a container a plugin
/// allocated.
class TargetFunction {
 public:
  /// The step h of the default derivative(), metres.
  static constexpr double derivative_step = 1e-6;

  virtual ~TargetFunction() = default;
  /// f(s) at each point; `out.size() == points.size()`. Points lie in the domain.
  virtual void evaluate(std::span<const double> points, std::span<double> out) const = 0;
  double operator()(double s) const {
    double value = 0;
    evaluate(std::span<const double>(&s, 1), std::span<double>(&value, 1));
    return value;
  }
  /// f'(s) at each point; `out.size() == points.size()`. Points lie in the domain.
  ///
  /// Default: the central difference (f(s + h) - f(s - h)) / (2h) with h = 1e-6 m, divided by
  /// the difference of the rounded arguments (exact, so rounding s +- h costs nothing while
  /// h >> eps |s|). Its error is h^2 |f'''| / 6 (truncation) plus about eps |f| / h (rounding of
  /// f): for a profile whose features have length l, relative to the slope scale |f| / l,
  /// (h / l)^2 / 6 + eps l / h, below 3e-9 for every l from 1 cm to 10 m. It evaluates f at
  /// s +- h, up to h outside the domain at an interval's ends: a target that cannot evaluate
  /// there overrides this. At a kink (kink_points) it averages the two one-sided slopes; no
  /// one-sided rule is needed, because an integrator that restarts at kinks takes its slopes
  /// inside the pieces between them. Targets with a closed form override it (and
  /// has_exact_derivative).
  virtual void derivative(std::span<const double> points, std::span<double> out) const {
    for (std::size_t m = 0; m < points.size(); ++m) {
      const double s = points[m];
      const double ahead = s + derivative_step, behind = s - derivative_step;
      out[m] = ((*this)(ahead) - (*this)(behind)) / (ahead - behind);
    }
  }
  /// True when derivative() is the derivative of f in closed form (not a difference).
  virtual bool has_exact_derivative() const { return false; }
  /// f'(s) at one point.
  double slope(double s) const {
    double value = 0;
    derivative(std::span<const double>(&s, 1), std::span<double>(&value, 1));
    return value;
  }
  /// Provenance of external data (e.g. "sha256:..." of a profile file): calls sink once with
  /// it, or not at all for a closed form (the default). A sink, not a returned string: nothing
  /// a plugin allocates is freed by the caller (plugin/module.hpp).
  virtual void describe_provenance(const std::function<void(std::string_view)>& sink) const {
    (void)sink;
  }
  /// Calls sink(s) for every arc length s in [0, L) where f is continuous but not smooth (e.g.
  /// the samples of a piecewise-linear profile, or the seam of a closed profile), in increasing
  /// order. An adaptive integrator that restarts at kinks (Integrator::restarts_at_kinks) also
  /// stops there. Default: none.
  virtual void list_kink_points(const std::function<void(double)>& sink) const { (void)sink; }
  /// Calls sink once per remark on how the target read its data, said once when the study is
  /// loaded (e.g. the columns of a CSV file it does not read). Default: none.
  virtual void list_notes(const std::function<void(std::string_view)>& sink) const { (void)sink; }

  // Conveniences on the caller's side of the boundary (they allocate here).

  /// describe_provenance as a string; empty for closed forms.
  std::string data_provenance() const {
    std::string out;
    describe_provenance([&](std::string_view text) { out = text; });
    return out;
  }
  /// list_kink_points as a vector.
  std::vector<double> kink_points() const {
    std::vector<double> out;
    list_kink_points([&](double s) { out.push_back(s); });
    return out;
  }
  /// list_notes as a vector.
  std::vector<std::string> notes() const {
    std::vector<std::string> out;
    list_notes([&](std::string_view note) { out.emplace_back(note); });
    return out;
  }
};

/// For a target of the arc length alone (a road profile): throws std::invalid_argument naming
/// `target` when the domain has d > 1. Called by such targets' constructors.
inline void require_track(const Domain& domain, std::string_view target) {
  if (domain.dimension != 1)
    throw std::invalid_argument(
        std::string("target '") + std::string(target) +
        "' is a function of the arc length s (d = 1); this domain has d = " +
        std::to_string(domain.dimension) +
        ": write f(x1, ..., xd) with the expression target (name = \"expression\")");
}

using TargetRegistry = Registry<TargetFunction, const Domain&>;
/// The target registry (defined in this layer, registries.cpp), named target_kind_name.
inline constexpr std::string_view target_kind_name = "target";
TargetRegistry& target_registry();

/// Registers target type T (static info(), constructor from ParameterSet and Domain). Never
/// throws; a failure is recorded in target_registry().errors() (register_plugin).
template <class T>
bool register_target() noexcept {
  return register_plugin<T>(target_registry());
}

}  // namespace rkhs

#define RKHS_REGISTER_TARGET(Type) \
  RKHS_REGISTRAR(rkhs_target_registered_, ::rkhs::register_target<Type>())
