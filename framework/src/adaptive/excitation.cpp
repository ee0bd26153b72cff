#include "rkhs/adaptive/excitation.hpp"

#include <stdexcept>

namespace rkhs {

namespace {
constexpr double eps = std::numeric_limits<double>::epsilon();
constexpr double resolution = 0.01;  // resolved: error_bound <= 1% of the value
}  // namespace

ExcitationLevel excitation_level(const Eigen::MatrixXd& excitation, const Eigen::MatrixXd& gram,
                                 const GramSpectrum& spectrum) {
  const Eigen::Index n = gram.rows();
  if (n == 0 || gram.cols() != n || excitation.rows() != n || excitation.cols() != n)
    throw std::invalid_argument("excitation_level: E and G must be square of the same size");
  ExcitationLevel out;
  out.dimension = n;
  if (spectrum.singular) return out;  // the H-norm is singular to working precision on H_n
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> pencil(
      excitation, gram, Eigen::Ax_lBx | Eigen::EigenvaluesOnly);
  if (pencil.info() != Eigen::Success) return out;  // G not numerically positive definite
  out.value = pencil.eigenvalues()(0);
  const double excitation_max =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(excitation, Eigen::EigenvaluesOnly)
          .eigenvalues()(n - 1);
  out.error_bound =
      eps * (excitation_max + std::abs(out.value) * spectrum.lambda_max) / spectrum.lambda_min;
  out.resolved = out.error_bound <= resolution * out.value;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double lambda = pencil.eigenvalues()(i);
    const double bound =
        eps * (excitation_max + std::abs(lambda) * spectrum.lambda_max) / spectrum.lambda_min;
    if (!(lambda > bound)) ++out.unexcited;
  }
  // No significant digit (a negative value among them): not a number to report.
  if (!(out.value > out.error_bound)) out.value = std::numeric_limits<double>::quiet_NaN();
  return out;
}

ExcitationLevel excitation_level_on_range(const Eigen::VectorXd& eigenvalues) {
  ExcitationLevel out;
  const Eigen::Index count = eigenvalues.size();
  if (count == 0) return out;
  const double largest = eigenvalues(count - 1);
  if (!(largest > 0)) return out;
  const double cutoff = static_cast<double>(count) * eps * largest;
  Eigen::Index first = 0;
  while (first < count && !(eigenvalues(first) > cutoff)) ++first;
  out.dimension = count - first;
  out.error_bound = cutoff;
  const double smallest = eigenvalues(first);
  out.resolved = smallest > cutoff / resolution;
  if (out.resolved) out.value = smallest;
  return out;
}

}  // namespace rkhs
