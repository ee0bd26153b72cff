#pragma once
// The structure of the coupled system's Jacobian, and exact solves with (c I - J) that use it.
//
// In z = [x (d), xhat (d), alpha (n)] the Jacobian of the coupled system (AdaptiveSystem) at
// one time t is a plant block and rank-one couplings:
//
//       [ A      0        0     ]
//   J = [ 0      A     B phi^T  ]     b = P B,  phi = phi(s(t)),  psi = psi(s(t)) = M phi
//       [ psi b^T  -psi b^T  0  ]
//
// so (c I - J) k = r, for a shift c (real in Rosenbrock stages, complex in Radau IIA's), is
// solved exactly by one d x d factorisation of (c I - A) and a Schur complement on one scalar:
//   k_x     = (c I - A)^-1 r_x
//   e       = b^T (k_x - k_xhat)        from  e (1 + beta (phi . psi) / c)
//                                              = b^T k_x - w^T r_xhat - beta (phi . r_alpha) / c
//   k_alpha = (r_alpha + psi e) / c
//   k_xhat  = (c I - A)^-1 r_xhat + u (phi . k_alpha)
// with u = (c I - A)^-1 B, w^T = b^T (c I - A)^-1 and beta = b^T u. Factorising costs O(d^3 + n)
// (the dot product phi . psi), each solve O(d^2 + n): no (2d + n)^2 matrix is formed.

#include <Eigen/Dense>
#include <complex>
#include <stdexcept>

namespace rkhs {

/// The Jacobian of the coupled system at one time, in structured form. A, B and b belong to
/// the system (they do not depend on t); phi and psi are phi(s(t)) and psi(s(t)).
struct CoupledLinearization {
  const Eigen::MatrixXd* A = nullptr;  ///< d x d
  const Eigen::VectorXd* B = nullptr;  ///< d
  const Eigen::VectorXd* b = nullptr;  ///< d, P B
  Eigen::VectorXd phi, psi;            ///< n each

  Eigen::Index plant_dimension() const noexcept { return A->rows(); }
  Eigen::Index dimension() const noexcept { return 2 * A->rows() + phi.size(); }
};

/// Thrown when c I - J is singular (the Schur complement vanishes or c I - A is singular).
class SingularStageMatrix : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Solves (c I - J) k = r for the J of a CoupledLinearization, Scalar = double or
/// std::complex<double>. factor() keeps a reference to the linearization: it must outlive
/// the solves. Nothing is allocated by solve() once the solver has been factored once at
/// this size.
template <class Scalar>
class ShiftedCoupledSolver {
 public:
  using Matrix = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
  using Vector = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;

  /// Factorises c I - J. Throws SingularStageMatrix when it is singular.
  void factor(const CoupledLinearization& linearization, Scalar shift) {
    lin_ = &linearization;
    shift_ = shift;
    const Eigen::Index d = linearization.plant_dimension();
    plant_matrix_ = -linearization.A->template cast<Scalar>();
    plant_matrix_.diagonal().array() += shift;
    plant_lu_.compute(plant_matrix_);
    const double pivot = plant_lu_.matrixLU().diagonal().cwiseAbs().minCoeff();
    if (!(pivot > 0)) throw SingularStageMatrix("c I - A is singular in a stage solve");
    u_ = plant_lu_.solve(linearization.B->template cast<Scalar>());
    // w^T = b^T (c I - A)^-1, i.e. w = (c I - A)^-T b.
    w_ = plant_lu_.transpose().solve(linearization.b->template cast<Scalar>());
    beta_ = linearization.b->template cast<Scalar>().dot(u_);
    const Scalar overlap = static_cast<Scalar>(linearization.phi.dot(linearization.psi));
    schur_ = Scalar(1) + beta_ * overlap / shift;
    if (!(std::abs(schur_) > 1e-300))
      throw SingularStageMatrix("the Schur complement of a stage solve vanishes");
    scratch_.resize(d);
  }

  /// Overwrites each column of `rhs` (dimension() rows) with the solution k of (c I - J) k = r.
  template <class Derived>
  void solve_in_place(Eigen::MatrixBase<Derived>& rhs) const {
    const Eigen::Index d = lin_->plant_dimension(), n = lin_->phi.size();
    const auto& phi = lin_->phi;
    const auto& psi = lin_->psi;
    const auto& b = *lin_->b;
    for (Eigen::Index j = 0; j < rhs.cols(); ++j) {
      auto column = rhs.col(j);
      auto rx = column.segment(0, d);
      auto rxhat = column.segment(d, d);
      auto ralpha = column.segment(2 * d, n);
      scratch_ = plant_lu_.solve(rx);  // k_x
      // Eigen's dot() conjugates its first argument: every dot below has a real vector first,
      // and the one product of two complex vectors (w^T r_xhat) is written as a plain sum.
      const Scalar right = (b.template cast<Scalar>().dot(scratch_) -
                            (w_.array() * rxhat.array()).sum()) -
                           beta_ * phi.template cast<Scalar>().dot(ralpha) / shift_;
      const Scalar e = right / schur_;
      rx = scratch_;
      ralpha = (ralpha + psi.template cast<Scalar>() * e) / shift_;
      const Scalar phi_k = phi.template cast<Scalar>().dot(ralpha);
      scratch_ = plant_lu_.solve(rxhat);
      rxhat = scratch_ + u_ * phi_k;
    }
  }

 private:
  const CoupledLinearization* lin_ = nullptr;
  Scalar shift_{};
  Matrix plant_matrix_;
  Eigen::PartialPivLU<Matrix> plant_lu_;
  Vector u_, w_;
  Scalar beta_{}, schur_{};
  mutable Vector scratch_;
};

}  // namespace rkhs
