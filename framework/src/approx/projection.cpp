// The projection operator's storage, the registry's entry point and the exact quantities of
// projection.hpp's form.
#include "rkhs/approx/projection.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "rkhs/core/parameters.hpp"

namespace rkhs {

void ProjectionOperator::resize(std::size_t dimension, std::size_t samples,
                                std::size_t basis_points, std::size_t point_dimension) {
  const auto dim = static_cast<Eigen::Index>(dimension);
  samples_.assign(samples * point_dimension, 0.0);
  basis_points_.assign(basis_points * point_dimension, 0.0);
  weights_ = Eigen::MatrixXd::Zero(dim, static_cast<Eigen::Index>(samples));
  basis_coefficients_ = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(basis_points), dim);
  mesh_.clear();
  solve_method_.clear();
  level = std::numeric_limits<double>::quiet_NaN();
}

void ProjectionOperator::set_mesh(std::span<const double> points) {
  mesh_.assign(points.begin(), points.end());
}

void ProjectionOperator::set_solve_method(std::string_view method) {
  solve_method_.assign(method.begin(), method.end());
}

void ProjectionMeasurement::add_flag(std::string_view flag) {
  flags_.emplace_back(flag);
}

void ProjectionMeasurement::set_solve_method(std::string_view method) {
  solve_method_.assign(method.begin(), method.end());
}

void Projection::measure(const ProjectionTrial&, ProjectionMeasurement&) const {
  throw std::logic_error(
      "Projection::measure called for a projection that is not matrix-free (it has an operator)");
}

std::optional<ProjectionFootprint> Projection::footprint(const AnyKernel&, std::size_t,
                                                         std::size_t) const {
  return std::nullopt;
}

std::string describe_projection(const ProjectionProperties& properties) {
  std::string out = properties.resolution == ProjectionResolution::level
                        ? "resolution: level j (n = n0 2^j cells)"
                        : "resolution: the n centres";
  out += properties.nested ? ", nested" : ", not nested";
  out += properties.h_orthogonal ? ", H-orthogonal" : ", not H-orthogonal";
  if (properties.operator_norm_bound)
    out += fmt::format(", ||Pi_j||_(H->H) <= {}", format_real(*properties.operator_norm_bound));
  if (!properties.requires_kernel.empty())
    out += fmt::format(", kernel: {}", properties.requires_kernel);
  if (properties.matrix_free) {
    std::vector<std::string_view> computed;
    for (const auto& row : MetricTable<ApproximationMetric>::rows)
      if (properties.measures & measured_metric_bit(row.id)) computed.push_back(row.name);
    out += fmt::format(", matrix-free (measures its trials itself; metrics: {})",
                       fmt::join(computed, ", "));
  }
  return out;
}

ProjectionOperator build_projection(std::string_view name, const ParameterSet& parameters,
                                    const ProjectionRequest& request) {
  const auto* entry = projection_registry().find(name);
  if (!entry) throw std::invalid_argument(fmt::format("unknown projection '{}'", name));
  const auto projection = entry->factory(parameters);
  const auto properties = projection->properties();
  if (!properties.requires_kernel.empty() && request.kernel.name() != properties.requires_kernel)
    throw std::invalid_argument(fmt::format(
        "projection '{}' works with the {} kernel only (its spaces are that kernel's levels), "
        "not with '{}'",
        name, properties.requires_kernel, request.kernel.name()));
  if (properties.matrix_free)
    throw std::invalid_argument(fmt::format(
        "projection '{}' is matrix-free: it has no operator W, E to build (it measures its "
        "trials itself, Projection::measure)",
        name));
  ProjectionOperator out;
  projection->build(request, out);
  const auto dim = static_cast<Eigen::Index>(out.dimension());
  if (dim == 0 || out.samples().empty() || out.basis_points().empty() ||
      out.basis_coefficients().cols() != dim)
    throw std::logic_error(
        fmt::format("projection '{}' built an empty or inconsistent operator "
                    "({} basis functions, {} samples, {} basis points)",
                    name, dim, out.sample_count(), out.basis_coefficients().rows()));
  if (!out.weights().allFinite() || !out.basis_coefficients().allFinite())
    throw std::runtime_error(
        fmt::format("projection '{}' built a non-finite operator (n = {})", name, request.n));
  return out;
}

void interpolation_operator(const AnyKernel& kernel, std::span<const double> centres,
                            const Eigen::MatrixXd& gram, const GramSolver& solver,
                            ProjectionOperator& out) {
  const auto d = static_cast<std::size_t>(kernel.domain().dimension);
  const auto n = centres.size() / d;
  const auto size = static_cast<Eigen::Index>(n);
  if (n == 0 || gram.rows() != size)
    throw std::invalid_argument("interpolation_operator: one Gram row per centre is needed");
  Eigen::MatrixXd E, W;  // W = E^T for the orthonormal bases
  if (const auto* vectors = solver.kept_vectors()) {
    E = *vectors * solver.kept_values()->cwiseSqrt().cwiseInverse().asDiagonal();
  } else if (solver.cholesky_lower()) {
    Eigen::MatrixXd inverse = Eigen::MatrixXd::Identity(size, size);
    solver.solve_lower_in_place(inverse);  // L^-1
    E = inverse.transpose();
  } else {  // regularised: G_mu^-1 through the solver, the basis k(c_i, .) itself
    E = Eigen::MatrixXd::Identity(size, size);
    W = solver.solve(E);
  }
  if (W.size() == 0) W = E.transpose();
  out.resize(static_cast<std::size_t>(E.cols()), n, n, d);
  std::copy(centres.begin(), centres.end(), out.samples().begin());
  std::copy(centres.begin(), centres.end(), out.basis_points().begin());
  out.basis_coefficients() = E;
  out.weights() = W;
  out.set_mesh(centres);
  out.set_solve_method(solver.method());
}

Eigen::MatrixXd projection_basis_values(const AnyKernel& kernel, const ProjectionOperator& op,
                                        std::span<const double> points) {
  return kernel.cross(points, op.basis_points()) * op.basis_coefficients();
}

Eigen::VectorXd apply_projection(const AnyKernel& kernel, const ProjectionOperator& op,
                                 const Eigen::VectorXd& at_samples,
                                 std::span<const double> points) {
  if (at_samples.size() != static_cast<Eigen::Index>(op.sample_count()))
    throw std::invalid_argument("apply_projection: one value per sample point is needed");
  const Eigen::VectorXd coefficients = op.weights() * at_samples;
  return kernel.cross(points, op.basis_points()) * (op.basis_coefficients() * coefficients);
}

namespace {
// G_B = E^T K_BB E for the kernel's Gram matrix K_BB on the basis points, symmetrised.
Eigen::MatrixXd basis_gram_of(const Eigen::MatrixXd& E, const Eigen::MatrixXd& K_BB) {
  Eigen::MatrixXd gram = E.transpose() * K_BB * E;
  return 0.5 * (gram + gram.transpose());
}

// A = W K_SS W^T (dim x dim): (A)_ik = (w_i, w_k) for the functionals w_i = sum_m W_im k(S_m, .)
// (the H-Riesz representers of f -> c_i), formed once so that what follows costs O(dim) per
// point instead of O(|S|).
Eigen::MatrixXd functional_gram_of(const Eigen::MatrixXd& W, const Eigen::MatrixXd& K_SS) {
  Eigen::MatrixXd A = W * (K_SS * W.transpose());
  return 0.5 * (A + A.transpose());
}

Eigen::MatrixXd functional_gram(const AnyKernel& kernel, const ProjectionOperator& op) {
  return functional_gram_of(op.weights(), kernel.gram(op.samples()));
}
}  // namespace

Eigen::MatrixXd projection_basis_gram(const AnyKernel& kernel, const ProjectionOperator& op) {
  return basis_gram_of(op.basis_coefficients(), kernel.gram(op.basis_points()));
}

Eigen::VectorXd projection_residual_norms(const AnyKernel& kernel, const ProjectionOperator& op,
                                          std::span<const double> points) {
  // With c = W^T D_m, D = E^T K_Y(points) (the basis at the points): c^T K_S(s_m) = (V)_m . D_m
  // with V = W K_S(points), and c^T K_SS c = D_m^T A D_m.
  const Eigen::MatrixXd D =
      op.basis_coefficients().transpose() * kernel.cross(op.basis_points(), points);
  const Eigen::MatrixXd V = op.weights() * kernel.cross(op.samples(), points);
  const Eigen::MatrixXd AD = functional_gram(kernel, op) * D;
  const Eigen::VectorXd diagonal = kernel.diagonal(points);
  Eigen::VectorXd out(static_cast<Eigen::Index>(kernel.domain().point_count(points)));
  for (Eigen::Index m = 0; m < out.size(); ++m) {
    // k - 2 D.V + D.AD, summed as (k - D.V) + D.(AD - V): for an H-orthogonal projection
    // AD = V, so the second term is round-off and the first is the power function's own
    // k(s, s) - k_X^T G^-1 k_X, without the cancellation of two large terms.
    const double squared =
        (diagonal[m] - D.col(m).dot(V.col(m))) + D.col(m).dot(AD.col(m) - V.col(m));
    out[m] = std::sqrt(std::max(0.0, squared));
  }
  return out;
}

double projection_norm_floor(const AnyKernel& kernel, std::size_t sample_count,
                             std::span<const double> points) {
  return std::sqrt(static_cast<double>(sample_count) * std::numeric_limits<double>::epsilon() *
                   kernel.diagonal(points).maxCoeff());
}

double projection_norm_floor(const AnyKernel& kernel, const ProjectionOperator& op,
                             std::span<const double> points) {
  return projection_norm_floor(kernel, op.sample_count(), points);
}

namespace {
// lambda_max of the symmetric positive semi-definite operator `apply` (y = M x) of size n: the
// Rayleigh quotient after 60 steps of the power method from a fixed start (deterministic, O(n)
// memory; a lower bound, close enough for the floors it serves).
template <class Apply>
double power_largest(Apply&& apply, Eigen::Index n) {
  if (n == 0) return 0.0;
  Eigen::VectorXd x(n), y(n);
  for (Eigen::Index i = 0; i < n; ++i) x(i) = 1.0 + 0.5 * std::sin(static_cast<double>(i + 1));
  x.normalize();
  double rayleigh = 0.0;
  for (int step = 0; step < 60; ++step) {
    apply(x, y);
    rayleigh = x.dot(y);
    const double length = y.norm();
    if (!(length > 0)) break;
    x = y / length;
  }
  return rayleigh;
}

// ||C||_2^2 = lambda_max(C^T C), through products with C and C^T (C^T C is never formed).
double squared_spectral_norm(const Eigen::MatrixXd& C) {
  Eigen::VectorXd Cx(C.rows());
  return power_largest(
      [&](const Eigen::VectorXd& x, Eigen::VectorXd& y) {
        Cx.noalias() = C * x;
        y.noalias() = C.transpose() * Cx;
      },
      C.cols());
}

// ||K||_inf, the largest absolute row sum: a bound of ||K||_2 for a symmetric K.
double infinity_norm(const Eigen::MatrixXd& K) {
  return K.size() ? K.cwiseAbs().rowwise().sum().maxCoeff() : 0.0;
}

// The amplification of round-off in the coefficients C of a Gram matrix C^T K C against the
// result's own size: ||C||_2^2 ||K||_inf / ||C^T K C||_2 (>= 1 up to round-off). Coefficients
// computed by solves with K (C = L^-T for an orthonormal basis) carry relative errors of about
// eps cond(K), and this ratio is cond(K) for them (||L^-T||^2 = 1 / lambda_min(K)); for
// coefficients that are data (the identity) it is about 1.
double coefficient_amplification(const Eigen::MatrixXd& C, double k_norm, double gram_norm) {
  if (!(gram_norm > 0)) return 1.0;
  return std::max(1.0, squared_spectral_norm(C) * k_norm / gram_norm);
}
}  // namespace

double projection_operator_norm(const AnyKernel& kernel, const ProjectionOperator& op,
                                double* floor) {
  // G_B = V diag(lambda) V^T, R = V diag(sqrt(lambda)) (round-off negatives clamped to 0);
  // ||Pi||^2 = lambda_max(R^T A R). G_B and A as projection_basis_gram and functional_gram form
  // them; of the kernel's Gram matrices only their norms are kept, for the floor (the
  // matrices themselves live no longer than in those two).
  const Eigen::MatrixXd& E = op.basis_coefficients();
  double basis_kernel_norm = 0, sample_kernel_norm = 0;
  Eigen::MatrixXd G_B;
  {
    const Eigen::MatrixXd K_B = kernel.gram(op.basis_points());
    G_B = basis_gram_of(E, K_B);
    if (floor) basis_kernel_norm = infinity_norm(K_B);
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> basis(G_B);
  G_B.resize(0, 0);
  const Eigen::MatrixXd R =
      basis.eigenvectors() * basis.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
  Eigen::MatrixXd A;
  {
    const Eigen::MatrixXd K_S = kernel.gram(op.samples());
    A = functional_gram_of(op.weights(), K_S);
    if (floor) sample_kernel_norm = infinity_norm(K_S);
  }
  Eigen::MatrixXd T = R.transpose() * A * R;
  T = 0.5 * (T + T.transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> norm(T, Eigen::EigenvaluesOnly);
  const double value = std::sqrt(std::max(0.0, norm.eigenvalues().maxCoeff()));
  if (floor) {
    const auto& lambda = basis.eigenvalues();
    const double dim = static_cast<double>(lambda.size());
    const double largest = lambda.size() ? lambda.maxCoeff() : 0.0;
    const double resolved = dim * std::numeric_limits<double>::epsilon() * largest;
    double smallest = largest;
    for (Eigen::Index i = 0; i < lambda.size(); ++i)
      if (lambda(i) > resolved) smallest = std::min(smallest, lambda(i));
    const double largest_of_A = power_largest(
        [&](const Eigen::VectorXd& x, Eigen::VectorXd& y) { y.noalias() = A * x; }, A.rows());
    // Round-off enters ||Pi||^2 through three matrices: G_B's eigendecomposition (cond(G_B)),
    // and the basis coefficients E and weights W, each amplified by the Gram matrix it was
    // built against (coefficient_amplification: cond(K) for coefficients that are solves).
    const double amplification =
        largest / smallest + coefficient_amplification(E, basis_kernel_norm, largest) +
        coefficient_amplification(op.weights().transpose(), sample_kernel_norm, largest_of_A);
    // Each entry of G_B and A sums over the basis points or samples, which may be more than dim
    // (a pseudo-inverse keeps dim < n directions of n samples).
    const double terms = std::max({dim, static_cast<double>(op.sample_count()),
                                   static_cast<double>(op.basis_coefficients().rows())});
    *floor = largest > 0
                 ? 0.5 * value * terms * std::numeric_limits<double>::epsilon() * amplification
                 : std::numeric_limits<double>::quiet_NaN();
  }
  return value;
}

}  // namespace rkhs
