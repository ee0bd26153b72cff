// One variant of rkhs::dense::Kernels (dense_kernels.hpp), compiled once per instruction set
// with RKHS_DENSE_VARIANT set to its table's name and RKHS_DENSE_ISA to its label. Eigen's
// namespace is renamed here so that nothing compiled for these instructions is shared with
// code compiled for others: include nothing else that defines inline functions or templates.
#if !defined(RKHS_DENSE_VARIANT) || !defined(RKHS_DENSE_ISA) || !defined(RKHS_DENSE_EIGEN)
#error "dense_kernels_variant.cpp is compiled through CMake, once per instruction set"
#endif

#define Eigen RKHS_DENSE_EIGEN
#define EIGEN_NO_IO 1
#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "rkhs/approx/dense_kernels.hpp"

namespace {

using Index = rkhs::dense::Index;
using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic>;
using Strided = Eigen::Map<Matrix, 0, Eigen::OuterStride<>>;
using ConstStrided = Eigen::Map<const Matrix, 0, Eigen::OuterStride<>>;

bool cholesky(double* a, Index n, Index lda) {
  Strided matrix(a, n, n, Eigen::OuterStride<>(lda));
  // Eigen's blocked right-looking factorisation of the lower triangle, in place.
  return Eigen::internal::llt_inplace<double, Eigen::Lower>::blocked(matrix) == -1;
}

bool cholesky_unblocked(double* a, Index n, Index lda) {
  Strided matrix(a, n, n, Eigen::OuterStride<>(lda));
  return Eigen::internal::llt_inplace<double, Eigen::Lower>::unblocked(matrix) == -1;
}

void solve_right_lower_transposed(const double* l, Index n, Index ldl, double* b, Index rows,
                                  Index ldb) {
  const ConstStrided factor(l, n, n, Eigen::OuterStride<>(ldl));
  Strided lhs(b, rows, n, Eigen::OuterStride<>(ldb));
  factor.transpose().triangularView<Eigen::Upper>().solveInPlace<Eigen::OnTheRight>(lhs);
}

void subtract_product_transposed(const double* a, Index m, Index k, Index lda, const double* b,
                                 Index n, Index ldb, double* c, Index ldc) {
  const ConstStrided left(a, m, k, Eigen::OuterStride<>(lda));
  const ConstStrided right(b, n, k, Eigen::OuterStride<>(ldb));
  Strided out(c, m, n, Eigen::OuterStride<>(ldc));
  out.noalias() -= left * right.transpose();
}

void subtract_gram_lower(const double* a, Index n, Index k, Index lda, double* c, Index ldc) {
  const ConstStrided left(a, n, k, Eigen::OuterStride<>(lda));
  Strided out(c, n, n, Eigen::OuterStride<>(ldc));
  out.selfadjointView<Eigen::Lower>().rankUpdate(left, -1.0);
}

void solve_lower(const double* l, Index n, Index ldl, double* b, Index cols, Index ldb) {
  const ConstStrided factor(l, n, n, Eigen::OuterStride<>(ldl));
  Strided rhs(b, n, cols, Eigen::OuterStride<>(ldb));
  factor.triangularView<Eigen::Lower>().solveInPlace(rhs);
}

void solve_lower_transposed(const double* l, Index n, Index ldl, double* b, Index cols, Index ldb) {
  const ConstStrided factor(l, n, n, Eigen::OuterStride<>(ldl));
  Strided rhs(b, n, cols, Eigen::OuterStride<>(ldb));
  factor.transpose().triangularView<Eigen::Upper>().solveInPlace(rhs);
}

void multiply(const double* a, Index m, Index k, Index lda, const double* b, Index n, Index ldb,
              double* c, Index ldc) {
  const ConstStrided left(a, m, k, Eigen::OuterStride<>(lda));
  const ConstStrided right(b, k, n, Eigen::OuterStride<>(ldb));
  Strided out(c, m, n, Eigen::OuterStride<>(ldc));
  out.noalias() = left * right;
}

}  // namespace

namespace rkhs::dense {
extern const Kernels RKHS_DENSE_VARIANT{RKHS_DENSE_ISA,
                                        cholesky,
                                        cholesky_unblocked,
                                        solve_right_lower_transposed,
                                        subtract_product_transposed,
                                        subtract_gram_lower,
                                        solve_lower,
                                        solve_lower_transposed,
                                        multiply};
}  // namespace rkhs::dense
