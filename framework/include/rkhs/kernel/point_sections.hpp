#pragma once
// The sections k(c_i, .) of a kernel on a domain of d = 2 or 3 dimensions, evaluated at one
// point y of R^d with their gradients: the basis phi(y) along a read-out y = C x + y0 of d > 1
// coordinates (docs/model.md section 18). KernelBasis is its one-dimensional counterpart (and
// also serves sparse feature maps and closed-form slopes along a track).

#include <Eigen/Dense>
#include <cstddef>
#include <span>
#include <stdexcept>
#include <string>

#include "rkhs/core/work_counters.hpp"
#include "rkhs/kernel/kernel.hpp"

namespace rkhs {

/// phi_i(y) = k(c_i, y) and grad phi_i(y) = grad_y k(c_i, y) for i < n, y in R^d.
///
/// Cost: n virtual calls per evaluate (AnyKernel::evaluate_point) and per gradient
/// (AnyKernel::gradient_point: the kernel's closed form where has_exact_gradient(), central
/// differences otherwise); nothing is allocated. Work counters (core/work_counters.hpp): an
/// evaluate counts n kernel evaluations, a gradient n x d derivative evaluations. A periodic domain is handled by the kernel
/// (its sections are periodic), so y need not be wrapped.
class PointSections {
 public:
  /// `kernel` and `centres` (flat: n points of d coordinates) must outlive the sections.
  /// Throws std::invalid_argument when centres.size() is not a multiple of d.
  PointSections(const AnyKernel& kernel, std::span<const double> centres)
      : kernel_(kernel), centres_(centres), d_(kernel.domain().dimension) {
    if (centres.size() % static_cast<std::size_t>(d_) != 0)
      throw std::invalid_argument(
          "PointSections: " + std::to_string(centres.size()) +
          " centre coordinates is not a whole number of points in d = " + std::to_string(d_));
    n_ = static_cast<Eigen::Index>(centres.size() / static_cast<std::size_t>(d_));
  }

  Eigen::Index size() const noexcept { return n_; }
  int dimension() const noexcept { return d_; }

  /// phi[i] = k(c_i, y); y has dimension() values, phi size() values.
  void evaluate(const double* y, double* phi) const {
    const auto d = static_cast<std::size_t>(d_);
    const std::span<const double> at(y, d);
    count_kernel_evaluations(static_cast<std::uint64_t>(n_));
    for (Eigen::Index i = 0; i < n_; ++i) phi[i] = kernel_.evaluate_point(centre(i), at);
  }

  /// The n x d Jacobian of phi, column-major: dphi[i + a n] = d/dy_a k(c_i, y) (column a is
  /// the n sections' slopes along axis a).
  void gradient(const double* y, double* dphi) const {
    const auto d = static_cast<std::size_t>(d_);
    const std::span<const double> at(y, d);
    double g[Domain::max_dimension] = {0, 0, 0};
    count_kernel_derivative_evaluations(static_cast<std::uint64_t>(n_) * d);
    for (Eigen::Index i = 0; i < n_; ++i) {
      kernel_.gradient_point(centre(i), at, std::span<double>(g, d));
      for (int a = 0; a < d_; ++a) dphi[i + a * n_] = g[a];
    }
  }

 private:
  std::span<const double> centre(Eigen::Index i) const noexcept {
    const auto d = static_cast<std::size_t>(d_);
    return centres_.subspan(static_cast<std::size_t>(i) * d, d);
  }

  const AnyKernel& kernel_;
  std::span<const double> centres_;
  int d_;
  Eigen::Index n_ = 0;
};

}  // namespace rkhs
