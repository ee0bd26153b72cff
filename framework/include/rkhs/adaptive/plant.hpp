#pragma once
// Plants x' = A x + B f(s(t)) (docs/model.md sections 1-2) and learning laws (eq. a3 and 4.2).

#include <Eigen/Dense>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "rkhs/core/registry.hpp"
#include "rkhs/kernel/kernel.hpp"

namespace rkhs {

/// A linear plant driven through B by the unknown function. A is Hurwitz (checked when the
/// plant is created: constructors throw std::invalid_argument otherwise).
class Plant {
 public:
  virtual ~Plant() = default;
  virtual const Eigen::MatrixXd& A() const noexcept = 0;  ///< d x d
  virtual const Eigen::VectorXd& B() const noexcept = 0;  ///< d
};

using PlantRegistry = Registry<Plant>;
PlantRegistry& plant_registry();

/// Where a learning law's coefficients live.
enum class LawCoordinates {
  /// alpha in R^n: fhat = sum_i alpha_i k(c_i, .) in H_n, the span of the sections at the
  /// trial's centres (gradient, rkhs).
  centres,
  /// beta in R^F: fhat = sum_f beta_f psi_f in the native space H itself, psi the kernel's
  /// finite feature map k(u, v) = sum_f psi_f(u) psi_f(v) (rkhs_embedding; docs/model.md
  /// section 14). The learning map is Gamma^-1 I: on the range of the feature evaluations, where
  /// the law keeps beta, ||fhat||_H^2 = beta^T beta.
  features,
};

/// The update of the coefficients alpha of fhat = sum_i alpha_i phi_i:
///   gradient: alpha' = Gamma^-1 phi(s) B^T P (x - xhat)          (eq. a3)
///   rkhs:     alpha' = Gamma^-1 G^-1 phi(s) B^T P (x - xhat)     (eq. 4.2)
/// and of the feature coordinates beta of fhat = sum_f beta_f psi_f:
///   rkhs_embedding: beta' = Gamma^-1 psi(s) B^T P (x - xhat)    (fhat' = Gamma^-1 k(s, .) ...)
/// with a scalar gain Gamma > 0.
class LearningLaw {
 public:
  virtual ~LearningLaw() = default;
  virtual bool uses_gram_inverse() const noexcept = 0;
  virtual double gain() const noexcept = 0;  ///< Gamma
  /// Where the coefficients live (centres unless the law says otherwise).
  virtual LawCoordinates coordinates() const noexcept { return LawCoordinates::centres; }
  /// Throws std::invalid_argument, naming the kernel, when the law cannot run with `kernel`
  /// (rkhs_embedding: a kernel without a finite feature map). Called before a trial runs.
  virtual void require_kernel(const AnyKernel& kernel) const { (void)kernel; }
  /// For feature coordinates with a kernel that has no finite feature map: the N of the
  /// reference resolution H_N that stands in for H (rkhs/adaptive/reference_resolution.hpp);
  /// 0 for none.
  virtual std::size_t reference_resolution() const noexcept { return 0; }
};

using LawRegistry = Registry<LearningLaw>;
LawRegistry& law_registry();

/// Parses a matrix written in a study file: "identity" (needs `size`), "diag(a, b, ...)", or
/// rows separated by ';' with entries separated by spaces or commas ("-1 0; 0 -2", "1; 0").
/// Throws std::invalid_argument saying what is wrong.
Eigen::MatrixXd parse_matrix(std::string_view text, Eigen::Index size = 0);

/// Register plant / learning-law type T (static info(), constructor from ParameterSet). Never
/// throw; a failure is recorded in the registry's errors() (register_plugin).
template <class T>
bool register_plant() noexcept {
  return register_plugin<T>(plant_registry());
}
template <class T>
bool register_law() noexcept {
  return register_plugin<T>(law_registry());
}

}  // namespace rkhs

#define RKHS_REGISTER_PLANT(Type) \
  RKHS_REGISTRAR(rkhs_plant_registered_, ::rkhs::register_plant<Type>())
#define RKHS_REGISTER_LAW(Type) RKHS_REGISTRAR(rkhs_law_registered_, ::rkhs::register_law<Type>())
