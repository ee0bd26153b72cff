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
// (the dot product phi . psi), each solve O(d^2 + n) per column: no (2d + n)^2 matrix is formed.

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
/// the solves. Nothing is allocated by solve_in_place() once it has solved a block of the same
/// number of columns.
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
    const Eigen::PartialPivLU<Matrix> lu(plant_matrix_);
    const double pivot = lu.matrixLU().diagonal().cwiseAbs().minCoeff();
    if (!(pivot > 0)) throw SingularStageMatrix("c I - A is singular in a stage solve");
    // (c I - A)^-1 explicitly: d is the plant's dimension (4 for the quarter car), and a d x d
    // product applies it to every column of a block at once.
    inverse_ = lu.inverse();
    b_ = linearization.b->template cast<Scalar>();
    phi_ = linearization.phi.template cast<Scalar>();
    psi_ = linearization.psi.template cast<Scalar>();
    u_.noalias() = inverse_ * linearization.B->template cast<Scalar>();
    // w^T = b^T (c I - A)^-1.
    w_.noalias() = inverse_.transpose() * b_;
    beta_ = (b_.transpose() * u_)(0);
    const Scalar overlap = static_cast<Scalar>(linearization.phi.dot(linearization.psi));
    schur_ = Scalar(1) + beta_ * overlap / shift;
    if (!(std::abs(schur_) > 1e-300))
      throw SingularStageMatrix("the Schur complement of a stage solve vanishes");
    (void)d;
  }

  /// Overwrites each column of `rhs` (dimension() rows) with the solution k of (c I - J) k = r.
  /// All columns at once: d x d and rank-one products over the block (no conjugation anywhere:
  /// every product below is the plain bilinear one).
  template <class Derived>
  void solve_in_place(Eigen::MatrixBase<Derived>& rhs) const {
    const Eigen::Index d = lin_->plant_dimension(), n = lin_->phi.size();
    auto rx = rhs.topRows(d);
    auto rxhat = rhs.middleRows(d, d);
    auto ralpha = rhs.bottomRows(n);
    kx_.noalias() = inverse_ * rx;
    // e = b^T (k_x - k_xhat), from e (1 + beta (phi . psi) / c)
    //   = b^T k_x - w^T r_xhat - beta (phi . r_alpha) / c.
    e_.noalias() = b_.transpose() * kx_;
    e_.noalias() -= w_.transpose() * rxhat;
    e_.noalias() -= (beta_ / shift_) * (phi_.transpose() * ralpha);
    e_ /= schur_;
    ralpha.noalias() += psi_ * e_;
    ralpha /= shift_;
    phi_k_.noalias() = phi_.transpose() * ralpha;
    kxhat_.noalias() = inverse_ * rxhat;
    kxhat_.noalias() += u_ * phi_k_;
    rxhat = kxhat_;
    rx = kx_;
  }

 private:
  using RowVector = Eigen::Matrix<Scalar, 1, Eigen::Dynamic>;
  const CoupledLinearization* lin_ = nullptr;
  Scalar shift_{};
  Matrix plant_matrix_, inverse_;
  Vector b_, phi_, psi_, u_, w_;
  Scalar beta_{}, schur_{};
  mutable Matrix kx_, kxhat_;
  mutable RowVector e_, phi_k_;
};

}  // namespace rkhs
