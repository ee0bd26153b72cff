#include "rkhs/approx/symmetric_eigen.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <utility>

#include "rkhs/core/cancellation.hpp"

namespace rkhs {

// Each step below is the corresponding code of Eigen 3.4's SelfAdjointEigenSolver.h,
// Tridiagonalization.h and HouseholderSequence.h for a real dynamic-size matrix, with the same
// expressions in the same order (so the same operations on the same operands: the build uses
// neither -ffast-math nor contraction into FMA here), and check_cancelled() between steps.
SymmetricEigen symmetric_eigen(const Eigen::MatrixXd& matrix, bool vectors) {
  using Eigen::Index;
  const Index n = matrix.cols();
  SymmetricEigen out;
  out.values.resize(n, 1);
  Eigen::MatrixXd& mat = out.vectors;  // SelfAdjointEigenSolver::m_eivec
  if (n == 1) {
    mat = matrix;
    out.values.coeffRef(0, 0) = mat.coeff(0, 0);
    if (vectors)
      mat.setOnes(n, n);
    else
      mat.resize(0, 0);
    return out;
  }
  Eigen::VectorXd& diag = out.values;

  // SelfAdjointEigenSolver::compute: the lower triangle mapped to [-1, 1].
  mat = matrix.triangularView<Eigen::Lower>();
  double scale = mat.cwiseAbs().maxCoeff();
  if (scale == 0.0) scale = 1.0;
  mat.triangularView<Eigen::Lower>() /= scale;
  Eigen::VectorXd subdiag(n - 1), hcoeffs(n - 1);

  // internal::tridiagonalization_inplace(matA, hCoeffs): one Householder step per column.
  for (Index i = 0; i < n - 1; ++i) {
    check_cancelled();
    const Index remaining = n - i - 1;
    double beta;
    double h;
    mat.col(i).tail(remaining).makeHouseholderInPlace(h, beta);
    mat.col(i).coeffRef(i + 1) = 1;
    hcoeffs.tail(n - i - 1).noalias() =
        (mat.bottomRightCorner(remaining, remaining).selfadjointView<Eigen::Lower>() *
         (h * mat.col(i).tail(remaining)));
    hcoeffs.tail(n - i - 1) +=
        (h * -0.5 * (hcoeffs.tail(remaining).dot(mat.col(i).tail(remaining)))) *
        mat.col(i).tail(n - i - 1);
    mat.bottomRightCorner(remaining, remaining)
        .selfadjointView<Eigen::Lower>()
        .rankUpdate(mat.col(i).tail(remaining), hcoeffs.tail(remaining), -1.0);
    mat.col(i).coeffRef(i + 1) = beta;
    hcoeffs.coeffRef(i) = h;
  }
  // internal::tridiagonalization_inplace_selector::run.
  diag = mat.diagonal();
  subdiag = mat.diagonal<-1>();
  if (vectors) {
    // mat = HouseholderSequence(mat, hCoeffs).setLength(n - 1).setShift(1): evalTo in place.
    using Sequence = Eigen::Tridiagonalization<Eigen::MatrixXd>::HouseholderSequenceType;
    Sequence sequence(mat, hcoeffs);
    sequence.setLength(n - 1).setShift(1);
    Eigen::VectorXd workspace(n);
    mat.diagonal().setOnes();
    mat.triangularView<Eigen::StrictlyUpper>().setZero();
    for (Index k = n - 2; k >= 0; --k) {
      check_cancelled();
      const Index corner = n - k - 1;
      mat.bottomRightCorner(corner, corner)
          .applyHouseholderOnTheLeft(sequence.essentialVector(k), hcoeffs.coeff(k),
                                     workspace.data());
      mat.col(k).tail(n - k - 1).setZero();
    }
    mat.col(0).tail(n - 1).setZero();  // the columns beyond the sequence's length: one
  }

  // internal::computeFromTridiagonal_impl: implicit symmetric QR steps with Wilkinson shifts.
  constexpr Index max_iterations = 30;  // SelfAdjointEigenSolver::m_maxIterations
  Index end = n - 1;
  Index start = 0;
  Index iter = 0;
  const double consider_as_zero = std::numeric_limits<double>::min();
  const double precision_inv = 1.0 / Eigen::NumTraits<double>::epsilon();
  while (end > 0) {
    check_cancelled();
    for (Index i = start; i < end; ++i) {
      if (std::abs(subdiag[i]) < consider_as_zero) {
        subdiag[i] = 0.0;
      } else {
        const double scaled_subdiag = precision_inv * subdiag[i];
        if (scaled_subdiag * scaled_subdiag <= (std::abs(diag[i]) + std::abs(diag[i + 1])))
          subdiag[i] = 0.0;
      }
    }
    while (end > 0 && subdiag[end - 1] == 0.0) end--;
    if (end <= 0) break;
    iter++;
    if (iter > max_iterations * n) break;
    start = end - 1;
    while (start > 0 && subdiag[start - 1] != 0) start--;
    Eigen::internal::tridiagonal_qr_step<Eigen::ColMajor>(
        diag.data(), subdiag.data(), start, end,
        vectors ? mat.data() : static_cast<double*>(nullptr), n);
  }
  out.info = iter <= max_iterations * n ? Eigen::Success : Eigen::NoConvergence;
  if (out.info == Eigen::Success) {
    // Selection sort, increasing (with the eigenvectors).
    for (Index i = 0; i < n - 1; ++i) {
      if (i % 64 == 0) check_cancelled();
      Index k;
      diag.segment(i, n - i).minCoeff(&k);
      if (k > 0) {
        std::swap(diag[i], diag[k + i]);
        if (vectors) mat.col(i).swap(mat.col(k + i));
      }
    }
  }
  out.values *= scale;
  if (!vectors) mat.resize(0, 0);
  return out;
}

}  // namespace rkhs
