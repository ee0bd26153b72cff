#pragma once
// Dense Cholesky factorisation and triangular solves at the speed of the processor the program
// runs on. One implementation (Eigen's blocked kernels, src/approx/dense_kernels_variant.cpp) is
// compiled three times: for any x86-64 (SSE2, the flags of the rest of the code), for AVX2 + FMA,
// and for AVX-512 (F, DQ, VL); kernels() picks one the first time it is called, from the
// processor's features (and the operating system's support for their registers). Measured on
// one core of an AVX-512 machine (n = 4096, 256 to 2048 right-hand sides a block): the
// triangular solves run at 15, 42 and 62-67 GFLOP/s; Debian's OpenBLAS 0.3.21 at 46 with the
// AVX2 kernels this machine's environment selects (OPENBLAS_CORETYPE=Haswell) and 66-74 with
// its AVX-512 ones; its DGEMM at 43-46 and 69-81 (docs/performance.md).
//
// Each variant lives in a namespace of its own (Eigen's namespace is renamed in its
// translation unit), so no instruction of one variant can reach another's code through a
// shared template instantiation; tests/architecture checks the objects for shared symbols.
// Results depend on the variant in their last bits (as they do on glibc's own run-time
// choice of exp and log), never on the thread count: each call is sequential, and
// parallel_cholesky splits its work into tiles that do not depend on the thread count.
//
// Matrices are column-major with a leading dimension; sizes are counts of rows and columns.

#include <cstddef>

namespace rkhs::dense {

using Index = std::ptrdiff_t;

struct Kernels {
  /// "x86-64", "avx2" or "avx512".
  const char* instruction_set;
  /// A = L L^T in place: the lower triangle of the n x n matrix `a` becomes L (the strict upper
  /// triangle is left as it was). False when A is not numerically positive definite (then `a`
  /// holds a partial factorisation).
  bool (*cholesky)(double* a, Index n, Index lda);
  /// The same without blocking (for the diagonal blocks of parallel_cholesky).
  bool (*cholesky_unblocked)(double* a, Index n, Index lda);
  /// B := B L^-T for the lower triangle L of `l` (n x n) and B rows x n.
  void (*solve_right_lower_transposed)(const double* l, Index n, Index ldl, double* b, Index rows,
                                       Index ldb);
  /// C := C - A B^T for A m x k, B n x k, C m x n.
  void (*subtract_product_transposed)(const double* a, Index m, Index k, Index lda, const double* b,
                                      Index n, Index ldb, double* c, Index ldc);
  /// The lower triangle of C (n x n) := that of C - A A^T for A n x k; the strict upper
  /// triangle of C is left as it was.
  void (*subtract_gram_lower)(const double* a, Index n, Index k, Index lda, double* c, Index ldc);
  /// B := L^-1 B for the lower triangle L of `l` (n x n) and B n x cols.
  void (*solve_lower)(const double* l, Index n, Index ldl, double* b, Index cols, Index ldb);
  /// B := L^-T B.
  void (*solve_lower_transposed)(const double* l, Index n, Index ldl, double* b, Index cols,
                                 Index ldb);
  /// C := A B for A m x k and B k x n (the speed of light the benchmarks compare with).
  void (*multiply)(const double* a, Index m, Index k, Index lda, const double* b, Index n,
                   Index ldb, double* c, Index ldc);
};

/// The variants compiled into this build (each in its own translation unit).
extern const Kernels baseline_kernels;
extern const Kernels avx2_kernels;
extern const Kernels avx512_kernels;

/// The widest variant the processor and operating system support, or the one named by the
/// environment variable RKHS_STUDY_DENSE_KERNELS ("x86-64", "avx2", "avx512"; one the processor
/// does not support is refused with a message on the standard error, and the widest is used).
/// Chosen once per process.
const Kernels& kernels() noexcept;

/// Whether this processor can run `variant`.
bool supported(const Kernels& variant) noexcept;

/// variant.cholesky's contract (A = L L^T in place, lower triangle; false when A is not
/// numerically positive definite), by Eigen's own right-looking blocked algorithm with its
/// block size, whose triangular solves and trailing updates are split into fixed tiles that
/// run through run_parts (rkhs/core/concurrency.hpp) on the idle threads of the caller's arena.
/// The tiles do not depend on the thread count, so neither does any bit of the result. Below
/// n = 512 it is variant.cholesky itself. It calls check_cancelled() (core/cancellation.hpp)
/// before each panel and each tile of a trailing update (milliseconds each at n = 6000): a
/// trial's passed deadline or stop request ends it there with the exception.
bool parallel_cholesky(const Kernels& variant, double* a, Index n, Index lda);

}  // namespace rkhs::dense
