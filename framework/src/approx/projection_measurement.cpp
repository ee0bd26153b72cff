// Approximation trials of a projection other than interpolation at the centres: an operator
// W, E built by its plugin and measured here (measure_projection), or a matrix-free projection
// measuring itself (measure_projection_trial).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "rkhs/approx/approximation.hpp"
#include "rkhs/approx/projection.hpp"
#include "rkhs/approx/sparse_gram.hpp"
#include "rkhs/core/cancellation.hpp"
#include "rkhs/core/concurrency.hpp"

namespace rkhs {
namespace {
constexpr double eps = std::numeric_limits<double>::epsilon();
constexpr double nan = std::numeric_limits<double>::quiet_NaN();
}  // namespace

void measure_projection_norms(const AnyKernel& kernel, const ProjectionOperator& op,
                              std::size_t evaluation_points, ApproximationMeasurement& out,
                              unsigned work) {
  using M = ApproximationMetric;
  const auto points = kernel.domain().uniform_points(evaluation_points);
  if (work & work_projection_residual) {
    const Eigen::VectorXd residual = projection_residual_norms(kernel, op, points);
    check_cancelled();
    const double norm = residual.maxCoeff();
    out.metrics[M::projection_norm_H_to_C] = norm;
    out.floors[M::projection_norm_H_to_C] = projection_norm_floor(kernel, op, points);
    if (norm <= out.floors[M::projection_norm_H_to_C])
      out.flags.push_back("projection_norm_at_floor");
  }
  if (work & work_operator_norm)
    out.metrics[M::projection_operator_norm] =
        projection_operator_norm(kernel, op, &out.floors[M::projection_operator_norm]);
}

ApproximationMeasurement measure_projection(const AnyKernel& kernel, const TargetFunction& target,
                                            const ProjectionOperator& op,
                                            std::size_t evaluation_points,
                                            const SolverOptions& solver_options,
                                            const MetricSelection& selection) {
  const unsigned work = work_needed<ApproximationMetric>(selection);
  const Domain& domain = kernel.domain();
  const auto points = domain.uniform_points(evaluation_points);
  const auto dim = static_cast<Eigen::Index>(op.dimension());
  ApproximationMeasurement out;
  using M = ApproximationMetric;
  auto& metrics = out.metrics;
  if (work & work_fill) metrics[M::fill_distance] = fill_distance(op.mesh(), domain);
  if (work & work_separation)
    metrics[M::separation_distance] = separation_distance(op.mesh(), domain);
  out.solve_method = op.solve_method();

  // H_j through the H-Gram matrix of its basis.
  const bool basis_gram = work & (work_spectrum | work_power | work_cardinal | work_interpolant);
  Eigen::MatrixXd gram;
  std::optional<GramSolver> solver;
  if (basis_gram) {
    gram = projection_basis_gram(kernel, op);
    check_cancelled();
    solver.emplace(gram, solver_options,
                   work & work_spectrum ? GramSpectrumMode::exact : GramSpectrumMode::estimate);
    const auto& spectrum = solver->spectrum();
    out.solve_method += "; basis: " + solver->method();
    record_spectrum_metrics(spectrum, static_cast<Eigen::Index>(dim), work, out);
  }

  // The power function of H_j: (b_i, k(s, .))_H = b_i(s).
  const bool power = work & (work_power | work_cardinal);
  const bool cardinal = work & work_cardinal;
  Eigen::MatrixXd values;  // M x dim
  if (power || (work & work_residual)) {
    values = projection_basis_values(kernel, op, points);
    check_cancelled();
  }
  const double round_off =
      solver ? static_cast<double>(dim) * eps * solver->spectrum().lambda_max : nan;
  double largest_solution_norm_squared = nan;
  if (power) {
    Eigen::VectorXd quadratic, solution_norm_squared;
    solver->quadratic_forms(values.transpose(), quadratic, solution_norm_squared);
    const Eigen::VectorXd power_squared = (kernel.diagonal(points) - quadratic).cwiseMax(0.0);
    largest_solution_norm_squared = solution_norm_squared.maxCoeff();
    const double power_sup = std::sqrt(power_squared.maxCoeff());
    const double power_floor = std::sqrt(round_off * largest_solution_norm_squared);
    metrics[M::power_function_sup] = power_sup;
    metrics[M::power_function_floor] = power_floor;
    out.floors[M::power_function_sup] = power_floor;
    out.floors[M::power_function_floor] = power_floor * solve_round_off(solver->spectrum(), dim);
    if (power_sup <= power_floor) out.flags.push_back("power_function_at_floor");
  }

  // Pi f = sum_i c_i b_i, c = W f(S).
  if (work & (work_interpolant | work_residual)) {
    const auto samples = op.samples();
    const std::size_t sample_count = op.sample_count(), point_count = domain.point_count(points);
    Eigen::VectorXd at_samples(static_cast<Eigen::Index>(sample_count));
    target.evaluate(samples, std::span<double>(at_samples.data(), sample_count));
    const Eigen::VectorXd coefficients = op.weights() * at_samples;
    const double error_floor =
        round_off * std::sqrt(largest_solution_norm_squared) * coefficients.norm();
    if (cardinal) {
      metrics[M::error_floor] = error_floor;
      out.floors[M::error_floor] = error_floor * solve_round_off(solver->spectrum(), dim);
    }
    if (work & work_interpolant) {
      const double native_norm = std::sqrt(std::max(0.0, coefficients.dot(gram * coefficients)));
      metrics[M::interpolant_native_norm] = native_norm;
      if (solver)
        out.floors[M::interpolant_native_norm] = native_norm_floor(
            native_norm, coefficients.squaredNorm(), at_samples.norm(), solver->spectrum(), dim);
    }
    if (work & work_residual) {
      Eigen::VectorXd at_points(static_cast<Eigen::Index>(point_count));
      target.evaluate(points, std::span<double>(at_points.data(), point_count));
      const Eigen::VectorXd residual = at_points - values * coefficients;
      const double l2 = domain.l2_norm(std::span<const double>(residual.data(), point_count));
      const double sup = residual.cwiseAbs().maxCoeff();
      metrics[M::l2_error] = l2;
      metrics[M::sup_error] = sup;
      if (cardinal) {
        out.floors[M::l2_error] = error_floor * std::sqrt(domain.volume());
        out.floors[M::sup_error] = error_floor;
      }
      if (cardinal && sup <= error_floor) out.flags.push_back("sup_error_at_floor");
      if (cardinal && l2 <= error_floor * std::sqrt(domain.volume()))
        out.flags.push_back("l2_error_at_floor");
    }
  }
  measure_projection_norms(kernel, op, evaluation_points, out, work);
  keep_selected(selection, out);
  return out;
}

std::vector<std::string> unmeasured_metrics(const ProjectionProperties& properties,
                                            const MetricSelection& selection) {
  std::vector<std::string> missing;
  const auto& rows = MetricTable<ApproximationMetric>::rows;
  for (std::size_t i = 0; i < rows.size(); ++i)
    if ((selection.empty() || (i < selection.size() && selection[i])) &&
        !(properties.measures & measured_metric_bit(rows[i].id)))
      missing.emplace_back(rows[i].name);
  return missing;
}

ApproximationMeasurement measure_projection_trial(
    std::string_view name, const ParameterSet& parameters, const ProjectionRequest& request,
    const TargetFunction& target, std::size_t evaluation_points, const MetricSelection& selection) {
  const auto* entry = projection_registry().find(name);
  if (!entry) throw std::invalid_argument(fmt::format("unknown projection '{}'", name));
  const auto projection = entry->factory(parameters);
  const auto properties = projection->properties();
  if (!properties.matrix_free) {
    const auto op = build_projection(name, parameters, request);
    check_cancelled();
    return measure_projection(request.kernel, target, op, evaluation_points, request.solver,
                              selection);
  }
  if (const auto missing = unmeasured_metrics(properties, selection); !missing.empty())
    throw std::invalid_argument(fmt::format(
        "projection '{}' is matrix-free and does not compute {}: leave them out of study.metrics",
        name, fmt::join(missing, ", ")));
  projection->check(request.kernel, request.n);
  const auto points = request.kernel.domain().uniform_points(evaluation_points);
  const ProjectionTrial trial{request.kernel, target,
                              request.n,      points,
                              request.solver, work_needed<ApproximationMetric>(selection)};
  ProjectionMeasurement measured;
  projection->measure(trial, measured);
  ApproximationMeasurement out;
  out.metrics = std::move(measured.metrics);
  out.floors = std::move(measured.floors);
  out.flags = measured.flags();
  out.solve_method = measured.solve_method();
  keep_selected(selection, out);
  return out;
}

}  // namespace rkhs
