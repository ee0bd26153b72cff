#pragma once
// Target functions: the unknown f the estimate approximates (a road profile in arc length).

#include <memory>
#include <span>
#include <string>
#include <vector>

#include "rkhs/core/domain.hpp"
#include "rkhs/core/registry.hpp"

namespace rkhs {

class TargetFunction {
 public:
  virtual ~TargetFunction() = default;
  /// f(s) at each point; `out.size() == points.size()`. Points lie in the domain.
  virtual void evaluate(std::span<const double> points, std::span<double> out) const = 0;
  double operator()(double s) const {
    double value = 0;
    evaluate(std::span<const double>(&s, 1), std::span<double>(&value, 1));
    return value;
  }
  /// Provenance of external data (e.g. "sha256:..." of a profile file); empty for closed forms.
  virtual std::string data_provenance() const { return {}; }
  /// Arc lengths in [0, L) where f is continuous but not smooth (e.g. the samples of a
  /// piecewise-linear profile, or the seam of a closed profile). An adaptive integrator that
  /// restarts at kinks (Integrator::restarts_at_kinks) also stops there. Default: none.
  virtual std::vector<double> kink_points() const { return {}; }
  /// Remarks on how the target read its data, said once when the study is loaded (e.g. the
  /// columns of a CSV file it does not read). Default: none.
  virtual std::vector<std::string> notes() const { return {}; }
};

using TargetRegistry = Registry<TargetFunction, const Domain&>;
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
