// Built-in learning laws: gradient (eq. a3) and rkhs (eq. 4.2), both with a scalar gain.
#include "rkhs/adaptive/plant.hpp"

namespace rkhs {
namespace {

/// alpha' = Gamma^-1 [G^-1] phi(s) B^T P (x - xhat) with a scalar gain: the gradient law
/// (eq. a3) without G^-1, the rkhs law (eq. 4.2) with it.
template <bool UsesGramInverse>
class ScalarGainLaw final : public LearningLaw {
 public:
  static PluginInfo info() {
    if constexpr (UsesGramInverse)
      return {"rkhs", "alpha' = Gamma^-1 G^-1 phi(s) B^T P (x - xhat) (eq. 4.2)",
              {positive_parameter("gamma", 1e-3, "the gain Gamma")}, {}};
    else
      return {"gradient", "alpha' = Gamma^-1 phi(s) B^T P (x - xhat) (eq. a3)",
              {positive_parameter("gamma", 1e-3, "the gain Gamma")}, {}};
  }
  explicit ScalarGainLaw(const ParameterSet& p) : gain_(p.real("gamma")) {}
  bool uses_gram_inverse() const noexcept override { return UsesGramInverse; }
  double gain() const noexcept override { return gain_; }

 private:
  double gain_;
};
using GradientLaw = ScalarGainLaw<false>;
using RkhsLaw = ScalarGainLaw<true>;

}  // namespace
}  // namespace rkhs

RKHS_REGISTER_LAW(rkhs::GradientLaw)
RKHS_REGISTER_LAW(rkhs::RkhsLaw)
