#include "rkhs/approx/approximation.hpp"

#include <algorithm>
#include <cmath>
#include <array>
#include <limits>
#include <queue>

#include "rkhs/core/cancellation.hpp"

namespace rkhs {

namespace {
constexpr double eps = std::numeric_limits<double>::epsilon();
constexpr double nan = std::numeric_limits<double>::quiet_NaN();

std::vector<double> sorted_wrapped(std::span<const double> centres, const Domain& domain) {
  std::vector<double> c(centres.size());
  std::transform(centres.begin(), centres.end(), c.begin(),
                 [&](double x) { return domain.wrap(x); });
  std::sort(c.begin(), c.end());
  return c;
}
}  // namespace

namespace {
// dist(x, X) = min_i |x - c_i| (the torus distance when periodic), by brute force.
double distance_to_set(const double* x, std::span<const double> centres, const Domain& domain) {
  const auto d = static_cast<std::size_t>(domain.dimension);
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < centres.size(); i += d)
    best = std::min(best, domain.squared_distance(x, centres.data() + i));
  return std::sqrt(best);
}

// sup_{x in Omega} dist(x, X) in d > 1 by branch and bound over boxes: dist(., X) is
// 1-Lipschitz, so over a box of centre c and half-diagonal r it is at most dist(c, X) + r.
// Boxes whose bound exceeds the best value found are split in 2^d; the search stops when no
// box can beat the best value by more than `relative_tolerance` of it.
double fill_distance_boxes(std::span<const double> centres, const Domain& domain) {
  constexpr double relative_tolerance = 1e-9;
  constexpr std::size_t initial_per_axis = 16;
  const int d = domain.dimension;
  struct Box {
    double bound;
    std::array<double, Domain::max_dimension> centre, half;
    bool operator<(const Box& other) const { return bound < other.bound; }
  };
  std::priority_queue<Box> queue;
  double best = 0.0;
  auto push = [&](const std::array<double, Domain::max_dimension>& centre,
                  const std::array<double, Domain::max_dimension>& half) {
    const double value = distance_to_set(centre.data(), centres, domain);
    best = std::max(best, value);
    double diagonal = 0.0;
    for (int a = 0; a < d; ++a) diagonal += half[a] * half[a];
    queue.push(Box{value + std::sqrt(diagonal), centre, half});
  };
  std::array<double, Domain::max_dimension> half{}, centre{};
  for (int a = 0; a < d; ++a) half[a] = 0.5 * domain.extent(a) / initial_per_axis;
  std::size_t total = 1;
  for (int a = 0; a < d; ++a) total *= initial_per_axis;
  for (std::size_t p = 0; p < total; ++p) {
    std::size_t rest = p;
    for (int a = 0; a < d; ++a) {
      centre[a] = (2.0 * static_cast<double>(rest % initial_per_axis) + 1.0) * half[a];
      rest /= initial_per_axis;
    }
    push(centre, half);
  }
  while (!queue.empty() && queue.top().bound > best * (1.0 + relative_tolerance)) {
    const Box box = queue.top();
    queue.pop();
    std::array<double, Domain::max_dimension> child_half{};
    for (int a = 0; a < d; ++a) child_half[a] = 0.5 * box.half[a];
    for (int corner = 0; corner < (1 << d); ++corner) {
      std::array<double, Domain::max_dimension> child{};
      for (int a = 0; a < d; ++a)
        child[a] = box.centre[a] + ((corner >> a) & 1 ? child_half[a] : -child_half[a]);
      push(child, child_half);
    }
  }
  return best;
}
}  // namespace

double fill_distance(std::span<const double> centres, const Domain& domain) {
  if (centres.empty()) return std::numeric_limits<double>::infinity();
  if (domain.dimension > 1) return fill_distance_boxes(centres, domain);
  const auto c = sorted_wrapped(centres, domain);
  double largest_gap = 0;
  for (std::size_t i = 1; i < c.size(); ++i) largest_gap = std::max(largest_gap, c[i] - c[i - 1]);
  if (domain.periodic) {
    largest_gap = std::max(largest_gap, c.front() + domain.length - c.back());
    return 0.5 * largest_gap;
  }
  return std::max({0.5 * largest_gap, c.front(), domain.length - c.back()});
}

double separation_distance(std::span<const double> centres, const Domain& domain) {
  if (domain.point_count(centres) < 2) return nan;
  if (domain.dimension > 1) {
    const auto d = static_cast<std::size_t>(domain.dimension);
    double smallest = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < centres.size(); i += d)
      for (std::size_t j = i + d; j < centres.size(); j += d)
        smallest = std::min(smallest, domain.squared_distance(centres.data() + i,
                                                              centres.data() + j));
    return 0.5 * std::sqrt(smallest);
  }
  const auto c = sorted_wrapped(centres, domain);
  double smallest_gap = std::numeric_limits<double>::infinity();
  for (std::size_t i = 1; i < c.size(); ++i) smallest_gap = std::min(smallest_gap, c[i] - c[i - 1]);
  if (domain.periodic) smallest_gap = std::min(smallest_gap, c.front() + domain.length - c.back());
  return 0.5 * smallest_gap;
}

const std::vector<std::string>& approximation_metric_names() {
  static const std::vector<std::string> names = metric_table_names<ApproximationMetric>();
  return names;
}

namespace {
// P_n^2 on the points, with what the error estimates need.
struct PowerFunctionData {
  Eigen::MatrixXd cross;                  // K_mi = k(s_m, c_i)
  Eigen::VectorXd power_squared;          // max(0, k(s,s) - k_X^T G^-1 k_X)
  Eigen::VectorXd solution_norm_squared;  // |G^-1 k_X(s_m)|^2
};

PowerFunctionData power_function_data(const AnyKernel& kernel, const GramSolver& solver,
                                      std::span<const double> centres,
                                      std::span<const double> points) {
  PowerFunctionData data;
  data.cross = kernel.cross(points, centres);
  Eigen::VectorXd quadratic;
  solver.quadratic_forms(data.cross.transpose(), quadratic, data.solution_norm_squared);
  data.power_squared = (kernel.diagonal(points) - quadratic).cwiseMax(0.0);
  return data;
}
}  // namespace

Eigen::VectorXd power_function(const AnyKernel& kernel, const GramSolver& solver,
                               std::span<const double> centres, std::span<const double> points) {
  return power_function_data(kernel, solver, centres, points).power_squared.cwiseSqrt();
}

ApproximationMeasurement measure_approximation(const AnyKernel& kernel,
                                               const TargetFunction& target,
                                               std::span<const double> centres,
                                               std::size_t evaluation_points,
                                               const SolverOptions& solver_options) {
  const Eigen::MatrixXd gram = kernel.gram(centres);
  check_cancelled();
  const GramSolver solver(gram, solver_options);
  check_cancelled();
  return measure_approximation(kernel, target, centres, evaluation_points, gram, solver);
}

ApproximationMeasurement measure_approximation(const AnyKernel& kernel,
                                               const TargetFunction& target,
                                               std::span<const double> centres,
                                               std::size_t evaluation_points,
                                               const Eigen::MatrixXd& gram,
                                               const GramSolver& solver,
                                               Eigen::MatrixXd* cross_out) {
  const Domain& domain = kernel.domain();
  const auto n = static_cast<Eigen::Index>(domain.point_count(centres));
  const auto points = domain.uniform_points(evaluation_points);
  const std::size_t point_count = domain.point_count(points);

  ApproximationMeasurement out;
  using M = ApproximationMetric;
  auto& metrics = out.metrics;
  metrics[M::fill_distance] = fill_distance(centres, domain);
  metrics[M::separation_distance] = separation_distance(centres, domain);

  const auto& spectrum = solver.spectrum();
  out.solve_method = solver.method();
  metrics[M::gram_condition_number] = spectrum.condition_number;
  metrics[M::gram_min_eigenvalue] = spectrum.lambda_min;
  metrics[M::gram_max_eigenvalue] = spectrum.lambda_max;
  if (spectrum.singular) out.flags.push_back("gram_singular");

  // Power function from the cross matrix K_mi = k(s_m, c_i), O(n^2) per point.
  auto data = power_function_data(kernel, solver, centres, points);
  check_cancelled();
  const Eigen::MatrixXd& cross = data.cross;
  const Eigen::VectorXd& solution_norm_squared = data.solution_norm_squared;
  const double round_off = static_cast<double>(n) * eps * spectrum.lambda_max;
  const double power_sup = std::sqrt(data.power_squared.maxCoeff());
  const double power_floor = std::sqrt(round_off * solution_norm_squared.maxCoeff());
  metrics[M::power_function_sup] = power_sup;
  metrics[M::power_function_floor] = power_floor;
  if (power_sup <= power_floor) out.flags.push_back("power_function_at_floor");

  // The interpolant Pi_n f = sum_i alpha_i k(c_i, .) with G alpha = f(X).
  Eigen::VectorXd at_centres(n), at_points(static_cast<Eigen::Index>(point_count));
  target.evaluate(centres, std::span<double>(at_centres.data(), static_cast<std::size_t>(n)));
  target.evaluate(points, std::span<double>(at_points.data(), point_count));
  const Eigen::VectorXd alpha = solver.solve(at_centres);
  const Eigen::VectorXd residual = at_points - cross * alpha;
  const double l2 = domain.l2_norm(std::span<const double>(residual.data(), point_count));
  const double sup = residual.cwiseAbs().maxCoeff();
  const double error_floor =
      round_off * std::sqrt(solution_norm_squared.maxCoeff()) * alpha.norm();
  metrics[M::l2_error] = l2;
  metrics[M::sup_error] = sup;
  metrics[M::error_floor] = error_floor;
  metrics[M::interpolant_native_norm] = std::sqrt(std::max(0.0, alpha.dot(gram * alpha)));
  if (sup <= error_floor) out.flags.push_back("sup_error_at_floor");
  if (l2 <= error_floor * std::sqrt(domain.volume())) out.flags.push_back("l2_error_at_floor");
  if (cross_out) *cross_out = std::move(data.cross);
  return out;
}

void measure_projection_norms(const AnyKernel& kernel, const ProjectionOperator& op,
                              std::size_t evaluation_points, ApproximationMeasurement& out) {
  using M = ApproximationMetric;
  const auto points = kernel.domain().uniform_points(evaluation_points);
  const Eigen::VectorXd residual = projection_residual_norms(kernel, op, points);
  check_cancelled();
  const double norm = residual.maxCoeff();
  out.metrics[M::projection_norm_H_to_C] = norm;
  out.metrics[M::projection_operator_norm] = projection_operator_norm(kernel, op);
  if (norm <= projection_norm_floor(kernel, op, points))
    out.flags.push_back("projection_norm_at_floor");
}

ApproximationMeasurement measure_projection(const AnyKernel& kernel, const TargetFunction& target,
                                            const ProjectionOperator& op,
                                            std::size_t evaluation_points,
                                            const SolverOptions& solver_options) {
  const Domain& domain = kernel.domain();
  const auto points = domain.uniform_points(evaluation_points);
  const auto dim = static_cast<Eigen::Index>(op.dimension());
  ApproximationMeasurement out;
  using M = ApproximationMetric;
  auto& metrics = out.metrics;
  metrics[M::fill_distance] = fill_distance(op.mesh(), domain);
  metrics[M::separation_distance] = separation_distance(op.mesh(), domain);

  // H_j through the H-Gram matrix of its basis.
  const Eigen::MatrixXd gram = projection_basis_gram(kernel, op);
  check_cancelled();
  const GramSolver solver(gram, solver_options);
  const auto& spectrum = solver.spectrum();
  out.solve_method = op.solve_method() + "; basis: " + solver.method();
  metrics[M::gram_condition_number] = spectrum.condition_number;
  metrics[M::gram_min_eigenvalue] = spectrum.lambda_min;
  metrics[M::gram_max_eigenvalue] = spectrum.lambda_max;
  if (spectrum.singular) out.flags.push_back("gram_singular");

  // The power function of H_j: (b_i, k(s, .))_H = b_i(s).
  const Eigen::MatrixXd values = projection_basis_values(kernel, op, points);  // M x dim
  check_cancelled();
  Eigen::VectorXd quadratic, solution_norm_squared;
  solver.quadratic_forms(values.transpose(), quadratic, solution_norm_squared);
  const Eigen::VectorXd power_squared = (kernel.diagonal(points) - quadratic).cwiseMax(0.0);
  const double round_off = static_cast<double>(dim) * eps * spectrum.lambda_max;
  const double power_sup = std::sqrt(power_squared.maxCoeff());
  const double power_floor = std::sqrt(round_off * solution_norm_squared.maxCoeff());
  metrics[M::power_function_sup] = power_sup;
  metrics[M::power_function_floor] = power_floor;
  if (power_sup <= power_floor) out.flags.push_back("power_function_at_floor");

  // Pi f = sum_i c_i b_i, c = W f(S).
  const auto samples = op.samples();
  const std::size_t sample_count = op.sample_count(), point_count = domain.point_count(points);
  Eigen::VectorXd at_samples(static_cast<Eigen::Index>(sample_count));
  Eigen::VectorXd at_points(static_cast<Eigen::Index>(point_count));
  target.evaluate(samples, std::span<double>(at_samples.data(), sample_count));
  target.evaluate(points, std::span<double>(at_points.data(), point_count));
  const Eigen::VectorXd coefficients = op.weights() * at_samples;
  const Eigen::VectorXd residual = at_points - values * coefficients;
  const double l2 = domain.l2_norm(std::span<const double>(residual.data(), point_count));
  const double sup = residual.cwiseAbs().maxCoeff();
  const double error_floor =
      round_off * std::sqrt(solution_norm_squared.maxCoeff()) * coefficients.norm();
  metrics[M::l2_error] = l2;
  metrics[M::sup_error] = sup;
  metrics[M::error_floor] = error_floor;
  metrics[M::interpolant_native_norm] =
      std::sqrt(std::max(0.0, coefficients.dot(gram * coefficients)));
  if (sup <= error_floor) out.flags.push_back("sup_error_at_floor");
  if (l2 <= error_floor * std::sqrt(domain.volume())) out.flags.push_back("l2_error_at_floor");
  measure_projection_norms(kernel, op, evaluation_points, out);
  return out;
}

}  // namespace rkhs
