#pragma once
// Helpers shared by the kernel tests: creating kernels through the registry, point sets, and the
// power function with a round-off tolerance.

#include <Eigen/Dense>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "rkhs/domain.hpp"
#include "rkhs/kernel.hpp"
#include "rkhs/parameters.hpp"

namespace rkhs::test {

using Given = std::map<std::string, ParameterValue>;

inline constexpr double epsilon = std::numeric_limits<double>::epsilon();
inline constexpr double pi = 3.14159265358979323846;
/// The paper's track: a circle of radius 4 m.
inline constexpr double track_length = 2 * pi * 4;

/// Creates `name` from the kernel registry with `given` parameters (others default).
inline std::unique_ptr<AnyKernel> make_registered_kernel(const std::string& name,
                                                         const Given& given, const Domain& domain) {
  const auto* entry = kernel_registry().find(name);
  REQUIRE(entry != nullptr);
  return entry->factory(ParameterSet::resolve(entry->info.parameters, given), domain);
}

/// The concrete kernel type K with `given` parameters, resolved against K's own declaration.
template <class K>
K make_kernel_of(const Given& given, const Domain& domain) {
  return K(ParameterSet::resolve(K::info().parameters, given), domain);
}

/// c_i = i L / n, i = 0..n-1: nested when n doubles, on both kinds of domain.
inline std::vector<double> uniform_centres(std::size_t n, double length) {
  std::vector<double> out(n);
  for (std::size_t i = 0; i < n; ++i)
    out[i] = static_cast<double>(i) * length / static_cast<double>(n);
  return out;
}

/// `count` points in [0, L) from the golden-ratio sequence: spread out, off every uniform grid.
inline std::vector<double> scattered_points(std::size_t count, double length,
                                            double start = 0.1234) {
  const double golden = 0.61803398874989484820;
  std::vector<double> out(count);
  double u = start;
  for (auto& s : out) {
    u += golden;
    u -= std::floor(u);
    s = u * length;
  }
  return out;
}

/// P_X(x)^2 = k(x, x) - k_X(x)^T G^+ k_X(x) at `points`, with G^+ the eigen-decomposition
/// pseudo-inverse (eigenvalues <= 1e3 n eps lambda_max dropped), and a round-off bound.
///
/// Bound: the computed quadratic form equals a^T (G + dG) a-type perturbations with
/// ||dG|| ~ n eps lambda_max and a = G^-1 k_X(x), ||a||^2 <= k(x, x) / lambda_min (because
/// a^T G a = k_X^T G^-1 k_X <= k(x, x)), so |error| <~ n eps (lambda_max / lambda_min) k(x, x).
/// `tolerance` = 32 n eps kappa max_x k(x, x), kappa over the eigenvalues kept.
struct PowerFunction {
  Eigen::VectorXd squared;
  double tolerance = 0;
  double condition = 0;  ///< lambda_max / smallest kept eigenvalue
  int dropped = 0;       ///< eigenvalues treated as zero
};

inline PowerFunction power_function_squared(const AnyKernel& kernel,
                                            const std::vector<double>& centres,
                                            const std::vector<double>& points) {
  const Eigen::MatrixXd gram = kernel.gram(centres);
  const auto n = static_cast<double>(centres.size());
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(gram);
  const Eigen::VectorXd& lambda = eigen.eigenvalues();
  const double lambda_max = lambda.maxCoeff();
  const double cutoff = 1e3 * n * epsilon * lambda_max;
  const Eigen::MatrixXd projections = kernel.cross(points, centres) * eigen.eigenvectors();
  const Eigen::VectorXd diagonal = kernel.diagonal(points);

  PowerFunction out;
  out.squared = diagonal;
  double lambda_min_kept = lambda_max;
  for (Eigen::Index i = 0; i < lambda.size(); ++i) {
    if (lambda(i) <= cutoff) {
      ++out.dropped;
      continue;
    }
    lambda_min_kept = std::min(lambda_min_kept, lambda(i));
    out.squared -= projections.col(i).cwiseAbs2() / lambda(i);
  }
  out.condition = lambda_max / lambda_min_kept;
  out.tolerance = 32 * n * epsilon * out.condition * diagonal.maxCoeff();
  return out;
}

}  // namespace rkhs::test
