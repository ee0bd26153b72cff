#pragma once
// Plants x' = A x + B f(s(t)) (docs/model.md sections 1-2), plants whose f is a function of
// their state, x' = A x + h(t, x) + B f(C x + y0) (section 18), and learning laws (eq. a3 and
// 4.2).

#include <Eigen/Dense>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "rkhs/core/registry.hpp"
#include "rkhs/kernel/kernel.hpp"

namespace rkhs {

/// A plant driven through B by the unknown function f. A is Hurwitz (checked when the plant is
/// created: constructors throw std::invalid_argument otherwise).
///
/// Two kinds (docs/model.md section 18):
///   road plants (readout() empty, the default): x' = A x + B f(s(t)), f of the arc length
///     s(t) along the path; linear in x.
///   state-dependent plants (readout() a p x d matrix C): x' = A x + h(t, x) + B f(C x + y0),
///     f of the read-out y = C x + y0 in the domain of the study (p = its dimension), with
///     known dynamics h (a forcing, a known nonlinearity). The estimator is
///     xhat' = A xhat + h(t, x) + B fhat(y), evaluated at the measured state x, so the state
///     error e = x - xhat obeys e' = A e + B (f - fhat)(y) as in the road case, and A is the
///     error dynamics the Lyapunov equation and the learning laws use.
class Plant {
 public:
  virtual ~Plant() = default;
  virtual const Eigen::MatrixXd& A() const noexcept = 0;  ///< d x d
  virtual const Eigen::VectorXd& B() const noexcept = 0;  ///< d

  /// C of the read-out y = C x + y0 (p x d), or an empty matrix for a road plant.
  virtual const Eigen::MatrixXd& readout() const noexcept { return no_matrix(); }
  /// y0 of the read-out (p values); empty for a road plant.
  virtual const Eigen::VectorXd& readout_offset() const noexcept { return no_vector(); }
  /// The known dynamics of a state-dependent plant at (t, x) (x: d values): writes h (d values)
  /// and, where the pointers are not null, dh/dx (d x d, row-major) and dh/dt (d values).
  /// Allocates nothing. Never called for a road plant. The default is h = 0.
  virtual void known_dynamics(double t, const double* x, double* h, double* dh_dx,
                              double* dh_dt) const {
    (void)t;
    (void)x;
    const auto d = static_cast<std::size_t>(A().rows());
    for (std::size_t i = 0; i < d; ++i) h[i] = 0;
    if (dh_dx)
      for (std::size_t i = 0; i < d * d; ++i) dh_dx[i] = 0;
    if (dh_dt)
      for (std::size_t i = 0; i < d; ++i) dh_dt[i] = 0;
  }
  /// The period of h in t, seconds (a forced oscillator's 2 pi / omega): one "lap" of a
  /// state-dependent trial. 0 when h has none (the trial then needs adaptive.final_time).
  virtual double period() const noexcept { return 0; }
  /// x(0) of the plant and of the estimator (d values; empty: zero).
  virtual const Eigen::VectorXd& initial_state() const noexcept { return no_vector(); }

  bool state_dependent() const noexcept { return readout().size() > 0; }

 private:
  static const Eigen::MatrixXd& no_matrix() noexcept {
    static const Eigen::MatrixXd none;
    return none;
  }
  static const Eigen::VectorXd& no_vector() noexcept {
    static const Eigen::VectorXd none;
    return none;
  }
};

using PlantRegistry = Registry<Plant>;
/// The plant registry (defined in this layer, registries.cpp), named plant_kind_name.
inline constexpr std::string_view plant_kind_name = "plant";
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
/// The learning-law registry (defined in this layer, registries.cpp), named law_kind_name.
inline constexpr std::string_view law_kind_name = "law";
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
