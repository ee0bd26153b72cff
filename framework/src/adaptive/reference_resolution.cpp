#include "rkhs/adaptive/reference_resolution.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "rkhs/kernel/mapped_basis.hpp"

namespace rkhs {

ReferenceResolvedKernel::ReferenceResolvedKernel(const AnyKernel& kernel, std::size_t resolution)
    : kernel_(kernel) {
  if (resolution == 0)
    throw std::invalid_argument("a reference resolution needs at least one centre");
  const Domain& domain = kernel.domain();
  centres_.resize(resolution);
  const double spacing =
      domain.periodic
          ? domain.length / static_cast<double>(resolution)
          : domain.length / static_cast<double>(std::max<std::size_t>(1, resolution - 1));
  for (std::size_t i = 0; i < resolution; ++i) centres_[i] = spacing * static_cast<double>(i);
  const Eigen::MatrixXd gram = kernel.gram(centres_);
  const GramSolver solver(gram, {});
  if (solver.spectrum().singular)
    throw std::invalid_argument(fmt::format(
        "the reference resolution {} (uniform centres standing in for H) gives kernel '{}' a "
        "Gram matrix singular to working precision (condition number {:.3g}): choose a smaller "
        "resolution",
        resolution, kernel.name(), solver.spectrum().condition_number));
  const Eigen::LLT<Eigen::MatrixXd> cholesky(gram);
  if (cholesky.info() != Eigen::Success)
    throw std::invalid_argument(fmt::format(
        "the reference resolution {} gives kernel '{}' a Gram matrix that is not numerically "
        "positive definite: choose a smaller resolution",
        resolution, kernel.name()));
  inverse_factor_ = cholesky.matrixL().solve(
      Eigen::MatrixXd(Eigen::MatrixXd::Identity(gram.rows(), gram.cols())));
}

std::unique_ptr<KernelBasis> ReferenceResolvedKernel::feature_basis() const {
  return std::make_unique<MappedBasis>([this] { return kernel_.basis(centres_); }, inverse_factor_);
}

double ReferenceResolvedKernel::norm_H_to_C(std::span<const double> points) const {
  const Eigen::MatrixXd features = kernel_.cross(points, centres_) * inverse_factor_.transpose();
  const Eigen::VectorXd diagonal = kernel_.diagonal(points);
  double out = 0;
  for (Eigen::Index m = 0; m < features.rows(); ++m)
    out = std::max(out, std::sqrt(std::max(0.0, diagonal(m) - features.row(m).squaredNorm())));
  return out;
}

}  // namespace rkhs
