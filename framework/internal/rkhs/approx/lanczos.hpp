#pragma once
// Lanczos estimates of the largest eigenvalue of a symmetric positive semi-definite operator:
// what GramSolver (dense) and the sparse path (sparse_approximation.cpp) scale round-off floors
// with and decide singularity from, the same iteration for both.

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <limits>

#include "rkhs/core/cancellation.hpp"

namespace rkhs {

// A fixed start vector with components in every direction (splitmix64 of the index, in
// [-1, 1)): Lanczos from it is deterministic, and no eigenvector of a structured Gram matrix
// (a constant or an alternating vector) is orthogonal to it.
inline Eigen::VectorXd lanczos_start(Eigen::Index n) {
  Eigen::VectorXd v(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    std::uint64_t z = static_cast<std::uint64_t>(i) + 0x9e3779b97f4a7c15ULL;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    v[i] = static_cast<double>(z >> 11) * 0x1.0p-52 - 1.0;
  }
  return v.normalized();
}

// The largest eigenvalue of the symmetric positive semi-definite operator `apply` (out = A in)
// of size n: the largest Ritz value of Lanczos with full reorthogonalisation, from
// lanczos_start, stopped when it changes by less than `tolerance` relative in one step, at an
// invariant subspace, or after `max_steps`. A Ritz value never exceeds the eigenvalue. Checks
// cancellation before every step (rkhs/core/cancellation.hpp).
template <class Apply>
double lanczos_largest(Apply&& apply, Eigen::Index n, double tolerance, Eigen::Index max_steps) {
  const Eigen::Index steps = std::min(n, max_steps);
  Eigen::MatrixXd basis(n, steps);
  basis.col(0) = lanczos_start(n);
  Eigen::VectorXd diagonal(steps), off_diagonal(steps), w(n);
  double ritz = 0;
  for (Eigen::Index k = 0; k < steps; ++k) {
    check_cancelled();  // a step is one product with G or one pair of solves: O(n^2)
    apply(basis.col(k), w);
    diagonal[k] = basis.col(k).dot(w);
    // Full reorthogonalisation, twice (Gram-Schmidt twice is enough).
    for (int pass = 0; pass < 2; ++pass)
      w.noalias() -= basis.leftCols(k + 1) * (basis.leftCols(k + 1).transpose() * w);
    const double beta = w.norm();
    double next = diagonal[0];
    if (k > 0) {
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> tridiagonal;
      const Eigen::VectorXd d = diagonal.head(k + 1), e = off_diagonal.head(k);
      tridiagonal.computeFromTridiagonal(d, e, Eigen::EigenvaluesOnly);
      next = tridiagonal.eigenvalues()[k];
    }
    const bool converged = k > 0 && std::abs(next - ritz) <= tolerance * std::abs(next);
    ritz = next;
    if (converged || beta <= std::numeric_limits<double>::epsilon() * std::abs(ritz) ||
        k + 1 == steps)
      break;
    off_diagonal[k] = beta;
    basis.col(k + 1) = w / beta;
  }
  return ritz;
}
}  // namespace rkhs
