#pragma once
// The symmetric eigen-decomposition of a Gram matrix, interruptible.
//
// Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> is one call that no deadline interrupts
// (seconds to minutes at n = 3000..6000). symmetric_eigen computes the same decomposition, bit
// for bit, as a loop over Eigen's own building blocks, the steps of
// SelfAdjointEigenSolver::compute (Eigen 3.4) in their order: the lower triangle scaled by its
// largest absolute entry; Householder tridiagonalisation (Eigen::internal::
// tridiagonalization_inplace); with eigenvectors, the accumulation of the Householder
// reflectors into Q (HouseholderSequence::evalTo, in place); the implicit symmetric QR
// iteration (internal::computeFromTridiagonal_impl, internal::tridiagonal_qr_step), its sort,
// and the eigenvalues scaled back. It calls check_cancelled() (core/cancellation.hpp) between
// Householder steps, between reflectors of the accumulation, between QR steps and between
// steps of the sort: each is O(n^2) at most (tens of milliseconds at n = 6000), so a passed
// deadline or a stop request ends the decomposition within that (TrialTimeLimitExceeded,
// TrialCancelled). tests/approx/test_symmetric_eigen.cpp compares it bit for bit with
// Eigen's solver.

#include <Eigen/Dense>

namespace rkhs {

struct SymmetricEigen {
  Eigen::VectorXd values;   ///< increasing (SelfAdjointEigenSolver::eigenvalues())
  Eigen::MatrixXd vectors;  ///< columns, with `values` (when asked for; else empty)
  Eigen::ComputationInfo info = Eigen::Success;
};

/// Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(matrix, vectors ? ComputeEigenvectors :
/// EigenvaluesOnly), bit for bit, reading the lower triangle of the square `matrix` (n >= 1),
/// with cancellation points (see the file comment).
SymmetricEigen symmetric_eigen(const Eigen::MatrixXd& matrix, bool vectors);

}  // namespace rkhs
