#pragma once
// Lanczos estimates of the largest eigenvalue of a symmetric positive semi-definite operator:
// what GramSolver (dense) and the sparse path (sparse_approximation.cpp) scale round-off floors
// with and decide singularity from, the same iteration for both.

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>

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

// Lanczos with full reorthogonalisation on the symmetric positive semi-definite operator
// `apply` (out = A in) of size n, from lanczos_start, for at most `max_steps` steps: after each
// step, `stop(ritz, previous, residual)` sees the largest Ritz value, the one before, and the
// residual |beta_k s_k| of its Ritz pair (an eigenvalue lies within it of the Ritz value); the
// iteration ends when it returns true, at an invariant subspace (residual 0), or after the last
// step. The residual is computed only `with_residual` (it needs the Ritz vectors; 1 otherwise).
// Returns the last largest Ritz value and whether `stop` ended it or the subspace was invariant.
// Checks cancellation before every step (rkhs/core/cancellation.hpp).
struct LanczosResult {
  double ritz = 0;
  bool resolved = false;
};
template <class Apply, class Stop>
LanczosResult lanczos_iterate(Apply&& apply, Eigen::Index n, Eigen::Index max_steps,
                              bool with_residual, Stop&& stop) {
  const Eigen::Index steps = std::min(n, max_steps);
  Eigen::MatrixXd basis(n, steps);
  basis.col(0) = lanczos_start(n);
  Eigen::VectorXd diagonal(steps), off_diagonal(steps), w(n);
  LanczosResult result;
  for (Eigen::Index k = 0; k < steps; ++k) {
    check_cancelled();  // a step is one product with G or one pair of solves: O(n^2)
    apply(basis.col(k), w);
    diagonal[k] = basis.col(k).dot(w);
    // Full reorthogonalisation, twice (Gram-Schmidt twice is enough).
    for (int pass = 0; pass < 2; ++pass)
      w.noalias() -= basis.leftCols(k + 1) * (basis.leftCols(k + 1).transpose() * w);
    const double beta = w.norm();
    double next = diagonal[0], last_component = 1;
    if (k > 0) {
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> tridiagonal;
      const Eigen::VectorXd d = diagonal.head(k + 1), e = off_diagonal.head(k);
      tridiagonal.computeFromTridiagonal(
          d, e, with_residual ? Eigen::ComputeEigenvectors : Eigen::EigenvaluesOnly);
      next = tridiagonal.eigenvalues()[k];
      if (with_residual) last_component = tridiagonal.eigenvectors()(k, k);
    }
    const double previous = result.ritz;
    result.ritz = next;
    const bool invariant = beta <= std::numeric_limits<double>::epsilon() * std::abs(next);
    if (invariant || (k > 0 && stop(next, previous, beta * std::abs(last_component)))) {
      result.resolved = true;
      break;
    }
    if (k + 1 == steps) break;
    off_diagonal[k] = beta;
    basis.col(k + 1) = w / beta;
  }
  return result;
}

// The largest eigenvalue of `apply` (lanczos_iterate), stopped when the largest Ritz value
// changes by less than `tolerance` relative in one step: an estimate (a Ritz value never
// exceeds the eigenvalue), what GramSolver's estimate mode and the sparse path's floors use.
template <class Apply>
double lanczos_largest(Apply&& apply, Eigen::Index n, double tolerance, Eigen::Index max_steps) {
  return lanczos_iterate(apply, n, max_steps, false,
                         [&](double ritz, double previous, double) {
                           return std::abs(ritz - previous) <= tolerance * std::abs(ritz);
                         })
      .ritz;
}

// The largest eigenvalue of `apply` to `tolerance` relative, resolved: stopped when the residual
// of the largest Ritz pair is at most `tolerance` times its Ritz value, so that an eigenvalue
// lies that close to it. Empty when `max_steps` pass first.
template <class Apply>
std::optional<double> lanczos_largest_resolved(Apply&& apply, Eigen::Index n, double tolerance,
                                               Eigen::Index max_steps) {
  const auto result = lanczos_iterate(
      apply, n, max_steps, true,
      [&](double ritz, double, double residual) { return residual <= tolerance * std::abs(ritz); });
  if (!result.resolved) return std::nullopt;
  return result.ritz;
}
}  // namespace rkhs
