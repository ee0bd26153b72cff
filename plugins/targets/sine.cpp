// Built-in closed-form targets.
#include <cmath>
#include <numbers>

#include "rkhs/approx/target.hpp"

namespace rkhs {
namespace {

/// f(s) = amplitude sin(2 pi cycles s / L + phase): the paper's synthetic road (model
/// section 2: amplitude 2, one cycle per lap).
class SineTarget final : public TargetFunction {
 public:
  static PluginInfo info() {
    return {"sine",
            "synthetic road f(s) = amplitude sin(2 pi cycles s / L + phase)",
            {real_parameter("amplitude", 2.0, "kappa, metres"),
             real_parameter("cycles", 1.0, "cycles per lap (an integer on a closed track)", 0.0),
             real_parameter("phase", 0.0, "phase, radians")},
            {}};
  }
  SineTarget(const ParameterSet& p, const Domain& domain)
      : amplitude_(p.real("amplitude")),
        wavenumber_(2.0 * std::numbers::pi * p.real("cycles") / domain.length),
        phase_(p.real("phase")) {
    require_track(domain, "sine");
    const double cycles = p.real("cycles");
    if (domain.periodic && cycles != std::round(cycles))
      throw ParameterError("cycles", "parameter 'cycles' must be a whole number on a closed "
                                     "track (f would not be periodic), found " +
                                         format_real(cycles));
  }
  void evaluate(std::span<const double> points, std::span<double> out) const override {
    for (std::size_t m = 0; m < points.size(); ++m)
      out[m] = amplitude_ * std::sin(wavenumber_ * points[m] + phase_);
  }
  /// f'(s) = amplitude (2 pi cycles / L) cos(2 pi cycles s / L + phase).
  void derivative(std::span<const double> points, std::span<double> out) const override {
    for (std::size_t m = 0; m < points.size(); ++m)
      out[m] = amplitude_ * wavenumber_ * std::cos(wavenumber_ * points[m] + phase_);
  }
  bool has_exact_derivative() const override { return true; }

 private:
  double amplitude_, wavenumber_, phase_;
};

}  // namespace
}  // namespace rkhs

RKHS_REGISTER_TARGET(rkhs::SineTarget)
