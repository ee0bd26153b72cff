// Built-in learning laws, all with a scalar gain: gradient (eq. a3) and rkhs (eq. 4.2) on the
// span H_n of the sections at the trial's centres, and rkhs_embedding, the infinite-dimensional
// estimator in H itself through the kernel's finite feature map (docs/model.md section 14).
#include <fmt/format.h>

#include <stdexcept>

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

/// The infinite-dimensional estimator fhat' = Gamma^-1 k(s, .) B^T P (x - xhat) in H itself,
/// exact for a kernel with a finite feature map k(u, v) = sum_f psi_f(u) psi_f(v): in feature
/// coordinates fhat = sum_f beta_f psi_f it is beta' = Gamma^-1 psi(s) B^T P (x - xhat), the
/// coupled system of the gradient law with the F features as its basis. The trial's centres
/// are not its basis (they still define the static metrics and Pi_n f).
class RkhsEmbeddingLaw final : public LearningLaw {
 public:
  static PluginInfo info() {
    return {"rkhs_embedding",
            "beta' = Gamma^-1 psi(s) B^T P (x - xhat): the estimator in H itself, "
            "fhat = sum_f beta_f psi_f over the kernel's features",
            {positive_parameter("gamma", 1e-3, "the gain Gamma"),
             integer_parameter("resolution", 0,
                               "for a kernel without a finite feature map: N uniform centres "
                               "whose span H_N stands in for H (its own error is reported as "
                               "reference_norm_H_to_C); 0: such kernels are refused",
                               0, 1 << 16)},
            {{"kernels", "with a finite feature map (bspline), exactly; others through a "
                         "reference resolution"},
             {"state", "2 d + F (F = the kernel's feature count), not 2 d + n"}}};
  }
  explicit RkhsEmbeddingLaw(const ParameterSet& p)
      : gain_(p.real("gamma")), resolution_(static_cast<std::size_t>(p.integer("resolution"))) {}
  std::size_t reference_resolution() const noexcept override { return resolution_; }
  bool uses_gram_inverse() const noexcept override { return false; }
  double gain() const noexcept override { return gain_; }
  LawCoordinates coordinates() const noexcept override { return LawCoordinates::features; }
  void require_kernel(const AnyKernel& kernel) const override {
    if (kernel.feature_count() == 0 && resolution_ == 0)
      throw std::invalid_argument(fmt::format(
          "learning law 'rkhs_embedding' needs a kernel with a finite feature map "
          "(k(u, v) = sum_f psi_f(u) psi_f(v)); kernel '{}' has none (use 'bspline', declare a "
          "reference resolution, resolution = N, or use the 'rkhs' law on H_n)",
          kernel.name()));
  }

 private:
  double gain_;
  std::size_t resolution_;
};

}  // namespace
}  // namespace rkhs

RKHS_REGISTER_LAW(rkhs::GradientLaw)
RKHS_REGISTER_LAW(rkhs::RkhsLaw)
RKHS_REGISTER_LAW(rkhs::RkhsEmbeddingLaw)
