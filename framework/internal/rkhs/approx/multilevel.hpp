#pragma once
// Multilevel (multiscale) interpolation with a compactly supported kernel (Floater and Iske
// 1996, Narcowich, Schaback and Ward 1999, Wendland 2010): nested tensor grids X_0 c X_1 c ...
// of the domain, m_j = m0 2^j (+ 1 on an interval: end points included) points per axis, spacing
// h_j = L_a / (m0 2^j) on axis a; on level j the kernel's support radius is rho_j = nu h_j
// (h_j the largest spacing over the axes), and s_j interpolates the residual
// e_{j-1} = f - s_0 - ... - s_{j-1} on X_j (e_{-1} = f). The sum s = s_0 + ... + s_J interpolates
// f on X_J.
//
// Each level's Gram matrix is assembled sparse (sparse_gram) and factorised by CHOLMOD; the
// residuals on the finest grid X_J and on the evaluation points are updated level by level from
// sparse cross matrices in chunks of points (sparse_cross_columns), never a dense n x n matrix.
// Deterministic: a point's value is the dot product of its cross column (stored in centre order)
// with the coefficients, whatever chunk or thread computes it.

#include <Eigen/Dense>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "rkhs/approx/projection.hpp"
#include "rkhs/approx/target.hpp"
#include "rkhs/kernel/kernel.hpp"

namespace rkhs {

struct MultilevelSettings {
  std::int64_t m0 = 4;  ///< intervals per axis of level 0
  double nu = 4.0;      ///< rho_j = nu h_j
};

/// How close the reported extreme eigenvalues of a level are known to lie to eigenvalues of its
/// Gram matrix, relative (Lanczos residual bound): part of level_condition_number's floor.
inline constexpr double multilevel_spectrum_tolerance = 1e-8;

/// What one level of a multilevel interpolation found.
struct MultilevelLevel {
  std::size_t centres = 0;
  double radius = 0;                   ///< rho_j
  double spacing = 0;                  ///< h_j, the largest grid spacing over the axes
  double l2_error = 0, sup_error = 0;  ///< of e_j on the evaluation points
  std::size_t nonzeros = 0;            ///< of level j's Gram matrix
  std::size_t factor_nonzeros = 0;     ///< of its Cholesky factor
  /// The extreme eigenvalues of the finest level's Gram matrix when asked for: Lanczos on G and
  /// on G^-1 through the factor until an eigenvalue lies within multilevel_spectrum_tolerance
  /// relative of the Ritz value; NaN when 300 steps do not get there.
  double lambda_min = std::numeric_limits<double>::quiet_NaN();
  double lambda_max = std::numeric_limits<double>::quiet_NaN();
  double factor_seconds = 0;      ///< assembly and factorisation
  double evaluation_seconds = 0;  ///< the cross matrices and residual updates
};

struct MultilevelResult {
  std::vector<MultilevelLevel> levels;
  double target_l2 = 0;                ///< ||f|| in L2 on the evaluation points (e_{-1})
  double target_sup = 0;               ///< max |f| on the evaluation points
  Eigen::VectorXd residual;            ///< e_J on the evaluation points
  Eigen::VectorXd finest_residual;     ///< e_J on X_J (round-off: s interpolates f there)
  std::vector<double> finest_centres;  ///< X_J
};

/// Points per axis of level j: m0 2^j, plus 1 on an interval.
std::size_t multilevel_points_per_axis(const Domain& domain, std::int64_t m0, int level);
/// Centres of level j: multilevel_points_per_axis^d.
std::size_t multilevel_centre_count(const Domain& domain, std::int64_t m0, int level);
/// The level j whose centre count is n, or -1 (levels up to 24).
int multilevel_level_of(const Domain& domain, std::int64_t m0, std::size_t n);

/// `kernel` with its parameter `radius` set to `radius` (through the kernel registry).
/// std::invalid_argument when the kernel has no parameter `radius` or global support.
std::unique_ptr<AnyKernel> kernel_with_radius(const AnyKernel& kernel, double radius);

/// The peak memory and work of multilevel_interpolation up to `finest_level` on
/// `evaluation_points` points, predicted before anything is built: per level j the sparse
/// path's prediction (predict_sparse_factor, sparse_gram.hpp) for its centres with the radius
/// nu h_j; the nonzeros and flops summed over the levels, the memory that of the largest level
/// (a level's matrices are freed before the next is assembled: its Gram matrix with its assembly,
/// CHOLMOD's copy and factor, the cross matrices of two chunks of points being updated) plus the
/// vectors kept throughout (X_J, the residuals on X_J and on the evaluation points, the points).
ProjectionFootprint predict_multilevel(const AnyKernel& kernel, const MultilevelSettings& settings,
                                       int finest_level, std::size_t evaluation_points);

/// Levels 0 .. finest_level of the multilevel interpolant of `target` (the kernel's other
/// parameters kept, its radius replaced per level), measured on `points`. With `spectra`, the
/// extreme eigenvalues of the finest level's Gram matrix (Lanczos; the others' stay NaN).
MultilevelResult multilevel_interpolation(const AnyKernel& kernel, const TargetFunction& target,
                                          const MultilevelSettings& settings, int finest_level,
                                          std::span<const double> points, bool spectra);

}  // namespace rkhs
