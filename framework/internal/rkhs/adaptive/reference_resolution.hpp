#pragma once
// The infinite-dimensional estimator for a kernel without a finite feature map (docs/model.md
// section 15): H is approached by H_N = span{k(c_i, .)} at N uniform centres, the declared
// reference resolution (`[[law]] name = "rkhs_embedding"`, `resolution = N`).
//
// H_N has the reproducing kernel k_N(u, v) = k(C, u)^T G^-1 k(C, v) = psi(u)^T psi(v) with the
// N orthonormal features psi = L^-1 k(C, .) (G = L L^T): a finite feature map. The adapter below
// is the kernel itself for every use but its features, which are these psi; with it the law's
// feature coordinates run unchanged (fhat = psi^T beta, ||fhat||_H = |beta|, exactly, since
// H_N is a subspace of H with H's norm). Its own error is that of Pi_N, the H-orthogonal
// projection onto H_N: Theorem 4.1 bounds the distance of the H_N estimator from the true one
// by its rate, ||I - Pi_N||_{H -> C} (the power function's sup), which the trial reports as
// reference_norm_H_to_C.

#include <Eigen/Dense>
#include <cstddef>
#include <memory>
#include <vector>

#include "rkhs/approx/gram_solver.hpp"
#include "rkhs/kernel/kernel.hpp"

namespace rkhs {

class ReferenceResolvedKernel final : public AnyKernel {
 public:
  /// H_N for `kernel` (which must outlive the adapter) at `resolution` uniform centres (offset
  /// 0). Throws std::invalid_argument when N is 0 or the Gram matrix of the centres is singular
  /// to working precision (no orthonormal features: a smaller N is needed).
  ReferenceResolvedKernel(const AnyKernel& kernel, std::size_t resolution);

  const std::string& name() const noexcept override { return kernel_.name(); }
  const ParameterSet& parameters() const noexcept override { return kernel_.parameters(); }
  const Domain& domain() const noexcept override { return kernel_.domain(); }
  const KernelProperties& properties() const noexcept override { return kernel_.properties(); }
  double evaluate(double x, double y) const override { return kernel_.evaluate(x, y); }
  double evaluate_point(std::span<const double> x, std::span<const double> y) const override {
    return kernel_.evaluate_point(x, y);
  }
  double derivative(double x, double y) const override { return kernel_.derivative(x, y); }
  bool has_exact_derivative() const noexcept override { return kernel_.has_exact_derivative(); }
  void gradient_point(std::span<const double> x, std::span<const double> y,
                      std::span<double> out) const override {
    kernel_.gradient_point(x, y, out);
  }
  bool has_exact_gradient() const noexcept override { return kernel_.has_exact_gradient(); }
  void gram_into(std::span<const double> centres, Eigen::Ref<Eigen::MatrixXd> out) const override {
    kernel_.gram_into(centres, out);
  }
  void cross_into(std::span<const double> points, std::span<const double> centres,
                  Eigen::Ref<Eigen::MatrixXd> out) const override {
    kernel_.cross_into(points, centres, out);
  }
  void diagonal_into(std::span<const double> points, std::span<double> out) const override {
    kernel_.diagonal_into(points, out);
  }
  std::unique_ptr<KernelBasis> basis(std::span<const double> centres) const override {
    return kernel_.basis(centres);
  }
  void list_kink_points(const std::function<void(double)>& sink) const override {
    kernel_.list_kink_points(sink);
  }
  /// N: the features of H_N.
  std::size_t feature_count() const noexcept override { return centres_.size(); }
  /// psi = L^-1 k(C, .), orthonormal in H.
  std::unique_ptr<KernelBasis> feature_basis() const override;

  const AnyKernel& kernel() const noexcept { return kernel_; }
  const std::vector<double>& centres() const noexcept { return centres_; }
  /// L^-1 (N x N), psi = L^-1 k(C, .): a function psi^T beta is sum_i (L^-T beta)_i k(c_i, .).
  const Eigen::MatrixXd& inverse_factor() const noexcept { return inverse_factor_; }
  /// ||I - Pi_N||_{H -> C} on `points`: max_m sqrt(k(s, s) - |psi(s)|^2) (clamped at 0).
  double norm_H_to_C(std::span<const double> points) const;

 private:
  const AnyKernel& kernel_;
  std::vector<double> centres_;
  Eigen::MatrixXd inverse_factor_;
};

}  // namespace rkhs
