#include "rkhs/approx/approximation.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <queue>

#include "rkhs/approx/sparse_gram.hpp"
#include "rkhs/core/cancellation.hpp"
#include "rkhs/core/concurrency.hpp"

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
// Evaluation points per block of the blocked pass: the cross matrix, the triangular solves and
// the residual are formed for this many points at a time (memory O(n^2 + n x block), never
// M x n), each block by itself, so the result does not depend on how blocks are scheduled.
// Measured at n = 4096 (one core): 512 is 5-10 % faster than 256 and 1024 (whose 32 MB blocks
// glibc maps afresh each time).
constexpr std::size_t points_per_block = 512;

// The sampled round-off floors (docs/metrics.md, "Floors"): where a trial reports neither
// power_function_floor nor error_floor, the second solve |G^-1 k_X(s_m)|^2 runs on every
// cardinal_sample_stride-th point (m = 0, 17, 34, ..., and the last point; 17 is prime, so on
// the tensor grids of domain.uniform_points the sample meets every row and column) and on the
// points that set power_function_sup and sup_error, not on every point.
constexpr std::size_t cardinal_sample_stride = 17;

bool in_cardinal_sample(std::size_t m, std::size_t point_count) {
  return m % cardinal_sample_stride == 0 || m + 1 == point_count;
}

// One pass over the evaluation points in blocks (run_parts: on idle threads of the trial's
// arena): the cross matrix K_b = k(s_b, X) of each block, then what `work` asks of it.
// `alpha` and `at_points` are needed for work_residual; `cross` (M x n), when not null,
// receives the whole cross matrix. With `sampled_cardinal` and a Cholesky factor, the second
// solve of work_cardinal runs only at the points in_cardinal_sample, and solution_norm_squared
// is 0 at the others (a lower bound: the floors are the maximum over the sample).
GridPass grid_pass(const AnyKernel& kernel, const GramSolver& solver,
                   std::span<const double> centres, std::span<const double> points, unsigned work,
                   const Eigen::VectorXd& alpha, const Eigen::VectorXd& at_points,
                   Eigen::MatrixXd* cross, bool sampled_cardinal = false) {
  const Domain& domain = kernel.domain();
  const auto d = static_cast<std::size_t>(domain.dimension);
  const std::size_t point_count = domain.point_count(points);
  const auto n = static_cast<Eigen::Index>(domain.point_count(centres));
  const auto m_total = static_cast<Eigen::Index>(point_count);
  const bool power = work & (work_power | work_cardinal);
  const bool cardinal = work & work_cardinal;
  const bool residual = work & work_residual;
  // The sample needs L^-1 k_X(s) from the first solve: a Cholesky factor (not the pseudo-inverse).
  const bool sampled = cardinal && sampled_cardinal && solver.kept_vectors() == nullptr;
  GridPass out;
  Eigen::VectorXd quadratic;
  if (power) {
    quadratic.resize(m_total);
    if (cardinal) out.solution_norm_squared.resize(m_total);
  }
  if (residual) out.residual.resize(m_total);
  if (cross) cross->resize(m_total, n);
  // The sampled points' L^-1 k_X(s_m), column m / stride (the last point after the others),
  // solved with L^T together after the pass: one wide triangular solve instead of thin ones.
  Eigen::MatrixXd sample;
  const auto sample_column = [&](std::size_t m) {
    return static_cast<Eigen::Index>(m % cardinal_sample_stride == 0 ? m / cardinal_sample_stride
                                                                     : sample.cols() - 1);
  };
  if (sampled) {
    const std::size_t strided = (point_count + cardinal_sample_stride - 1) / cardinal_sample_stride;
    const bool last_extra = (point_count - 1) % cardinal_sample_stride != 0;
    sample.resize(n, static_cast<Eigen::Index>(strided + (last_extra ? 1 : 0)));
    out.solution_norm_squared.setZero();
  }
  const std::size_t blocks = (point_count + points_per_block - 1) / points_per_block;
  run_parts(blocks, [&](std::size_t b) {
    const std::size_t first = b * points_per_block;
    const std::size_t rows = std::min(points_per_block, point_count - first);
    const auto offset = static_cast<Eigen::Index>(first), count = static_cast<Eigen::Index>(rows);
    const auto block_points = points.subspan(first * d, rows * d);
    Eigen::MatrixXd local;
    if (!cross) local.resize(count, n);
    Eigen::Ref<Eigen::MatrixXd> block =
        cross ? Eigen::Ref<Eigen::MatrixXd>(cross->middleRows(offset, count))
              : Eigen::Ref<Eigen::MatrixXd>(local);
    kernel.cross_into(block_points, centres, block);
    check_cancelled();
    if (residual)
      out.residual.segment(offset, count).noalias() =
          at_points.segment(offset, count) - block * alpha;
    if (power && sampled) {
      Eigen::MatrixXd columns = block.transpose();
      solver.quadratic_forms_in_place(columns, quadratic.data() + offset, nullptr);
      // columns holds L^-1 k_X(s) now: keep the sampled ones for the second solve below.
      for (std::size_t i = 0; i < rows; ++i)
        if (in_cardinal_sample(first + i, point_count))
          sample.col(sample_column(first + i)) = columns.col(static_cast<Eigen::Index>(i));
      check_cancelled();
    } else if (power) {
      Eigen::MatrixXd columns = block.transpose();
      solver.quadratic_forms_in_place(columns, quadratic.data() + offset,
                                      cardinal ? out.solution_norm_squared.data() + offset
                                               : nullptr);
      check_cancelled();
    }
  });
  if (sampled) {
    const auto columns = static_cast<std::size_t>(sample.cols());
    const std::size_t parts = (columns + points_per_block - 1) / points_per_block;
    run_parts(parts, [&](std::size_t part) {
      const auto first = static_cast<Eigen::Index>(part * points_per_block);
      const auto count =
          static_cast<Eigen::Index>(std::min(points_per_block, columns - part * points_per_block));
      solver.solve_lower_transposed_in_place(sample.middleCols(first, count));
      check_cancelled();
    });
    for (std::size_t m = 0; m < point_count; ++m)
      if (in_cardinal_sample(m, point_count))
        out.solution_norm_squared(static_cast<Eigen::Index>(m)) =
            sample.col(sample_column(m)).squaredNorm();
  }
  if (power) out.power_squared = (kernel.diagonal(points) - quadratic).cwiseMax(0.0);
  return out;
}

// |G^-1 k_X(s_m)|^2 exactly at the points that set power_function_sup and sup_error, into
// pass.solution_norm_squared: with the sample of grid_pass, the floors' maximum includes them.
void cardinal_at_sup_points(const AnyKernel& kernel, const GramSolver& solver,
                            std::span<const double> centres, std::span<const double> points,
                            GridPass& pass) {
  const auto d = static_cast<std::size_t>(kernel.domain().dimension);
  const auto n = static_cast<Eigen::Index>(kernel.domain().point_count(centres));
  std::array<Eigen::Index, 2> at{-1, -1};
  if (pass.power_squared.size() > 0) pass.power_squared.maxCoeff(&at[0]);
  if (pass.residual.size() > 0) pass.residual.cwiseAbs().maxCoeff(&at[1]);
  for (const Eigen::Index m : at) {
    if (m < 0) continue;
    Eigen::MatrixXd row(1, n);
    kernel.cross_into(points.subspan(static_cast<std::size_t>(m) * d, d), centres, row);
    Eigen::MatrixXd column = row.transpose();
    double quadratic = 0;
    solver.quadratic_forms_in_place(column, &quadratic, &pass.solution_norm_squared(m));
  }
}

}  // namespace

// The floor of ||Pi f||_H = sqrt(alpha^T G alpha): the larger of what a backward error E of
// n eps lambda_max in G moves it by (alpha^T E alpha in the square) and what the round-off of the
// data, eps |f(X)|, becomes through the smallest eigenvalue the solve keeps (lambda_min, at least
// the n eps lambda_max a singular G is cut at): eps |f(X)| / sqrt(that).
double native_norm_floor(double norm, double coefficients_squared, double data_norm,
                         const GramSpectrum& spectrum, Eigen::Index n) {
  const double perturbation = static_cast<double>(n) * eps * spectrum.lambda_max;
  const double backward = norm > 0 ? perturbation * coefficients_squared / (2 * norm)
                                   : std::sqrt(perturbation * coefficients_squared);
  const double kept = std::max(spectrum.lambda_min, perturbation);
  const double data = kept > 0 ? eps * data_norm / std::sqrt(kept) : 0.0;
  return std::max(backward, data);
}

namespace {
// The floors of the extreme eigenvalues (Weyl: a perturbation of G by n eps lambda_max moves
// each by at most that much) and of their ratio.
void set_spectrum_floors(const GramSpectrum& spectrum, double n,
                         MetricValues<ApproximationMetric>& floors) {
  using M = ApproximationMetric;
  const double perturbation = n * eps * spectrum.lambda_max;
  floors[M::gram_min_eigenvalue] = perturbation;
  floors[M::gram_max_eigenvalue] = perturbation;
  floors[M::gram_condition_number] =
      spectrum.lambda_min > 0 ? spectrum.condition_number * perturbation / spectrum.lambda_min
                              : std::numeric_limits<double>::infinity();
}
}  // namespace

void record_spectrum_metrics(const GramSpectrum& spectrum, Eigen::Index n, unsigned work,
                             ApproximationMeasurement& out) {
  using M = ApproximationMetric;
  if (work & work_spectrum) {
    out.metrics[M::gram_condition_number] = spectrum.condition_number;
    out.metrics[M::gram_min_eigenvalue] = spectrum.lambda_min;
    out.metrics[M::gram_max_eigenvalue] = spectrum.lambda_max;
    set_spectrum_floors(spectrum, static_cast<double>(n), out.floors);
  }
  if (spectrum.singular) out.flags.push_back("gram_singular");
}

// Leaves NaN in every metric `selection` does not name (MetricSelection; empty: keep all), so
// a trial's record holds exactly what it was asked to compute.
void keep_selected(const MetricSelection& selection, ApproximationMeasurement& out) {
  if (selection.empty()) return;
  for (std::size_t i = 0; i < MetricValues<ApproximationMetric>::count; ++i)
    if (i >= selection.size() || !selection[i]) {
      out.metrics[static_cast<ApproximationMetric>(i)] = nan;
      out.floors[static_cast<ApproximationMetric>(i)] = nan;
    }
}

void record_interpolant_metrics(const AnyKernel& kernel, std::span<const double> points,
                                Eigen::Index n, const GramSpectrum& spectrum, unsigned work,
                                const Eigen::VectorXd& alpha, double native_norm_squared,
                                double target_norm_at_centres, const GridPass& pass,
                                ApproximationMeasurement& out) {
  using M = ApproximationMetric;
  const Domain& domain = kernel.domain();
  auto& metrics = out.metrics;
  record_spectrum_metrics(spectrum, n, work, out);
  const double round_off = static_cast<double>(n) * eps * spectrum.lambda_max;
  const bool cardinal = work & work_cardinal;
  const double largest_solution_norm_squared =
      cardinal ? pass.solution_norm_squared.maxCoeff() : nan;
  if (work & (work_power | work_cardinal)) {
    const double power_sup = std::sqrt(pass.power_squared.maxCoeff());
    const double power_floor = std::sqrt(round_off * largest_solution_norm_squared);
    metrics[M::power_function_sup] = power_sup;
    metrics[M::power_function_floor] = power_floor;
    out.floors[M::power_function_sup] = power_floor;
    out.floors[M::power_function_floor] = power_floor * solve_round_off(spectrum, n);
    if (cardinal && power_sup <= power_floor) out.flags.push_back("power_function_at_floor");
  }
  if (work & work_interpolant) {
    const double native_norm = std::sqrt(std::max(0.0, native_norm_squared));
    metrics[M::interpolant_native_norm] = native_norm;
    out.floors[M::interpolant_native_norm] =
        native_norm_floor(native_norm, alpha.squaredNorm(), target_norm_at_centres, spectrum, n);
    if (cardinal) {
      metrics[M::error_floor] = round_off * std::sqrt(largest_solution_norm_squared) * alpha.norm();
      out.floors[M::error_floor] = metrics[M::error_floor] * solve_round_off(spectrum, n);
    }
  }
  if (work & work_residual) {
    const Eigen::VectorXd& residual = pass.residual;
    const double l2 = domain.l2_norm(
        std::span<const double>(residual.data(), static_cast<std::size_t>(residual.size())));
    const double sup = residual.cwiseAbs().maxCoeff();
    metrics[M::l2_error] = l2;
    metrics[M::sup_error] = sup;
    out.floors[M::l2_error] = metrics[M::error_floor] * std::sqrt(domain.volume());
    out.floors[M::sup_error] = metrics[M::error_floor];
    if (cardinal) {
      const double error_floor = metrics[M::error_floor];
      if (sup <= error_floor) out.flags.push_back("sup_error_at_floor");
      if (l2 <= error_floor * std::sqrt(domain.volume())) out.flags.push_back("l2_error_at_floor");
    }
  }
  // ||I - Pi_n||_{H -> C} of the H-orthogonal projection onto span{k(c_i, .)} is the power
  // function (projection.hpp; tests/approx check it against the operator's own definition).
  if (work & work_projection_residual) {
    const double norm = metrics[M::power_function_sup];
    metrics[M::projection_norm_H_to_C] = norm;
    out.floors[M::projection_norm_H_to_C] =
        projection_norm_floor(kernel, static_cast<std::size_t>(n), points);
    if (norm <= out.floors[M::projection_norm_H_to_C])
      out.flags.push_back("projection_norm_at_floor");
  }
}

namespace {

// measure_approximation on a built Gram matrix and solver, computing what `work` asks.
ApproximationMeasurement measure_interpolant(const AnyKernel& kernel, const TargetFunction& target,
                                             std::span<const double> centres,
                                             std::size_t evaluation_points,
                                             const Eigen::MatrixXd& gram, const GramSolver& solver,
                                             unsigned work, Eigen::MatrixXd* cross_out,
                                             bool sampled_cardinal = false) {
  // ||I - Pi_n||_{H -> C} of interpolation is the power function (below).
  if (work & work_projection_residual) work |= work_power;
  const Domain& domain = kernel.domain();
  const auto n = static_cast<Eigen::Index>(domain.point_count(centres));
  const auto points = domain.uniform_points(evaluation_points);
  const std::size_t point_count = domain.point_count(points);

  ApproximationMeasurement out;
  using M = ApproximationMetric;
  auto& metrics = out.metrics;
  if (work & work_fill) metrics[M::fill_distance] = fill_distance(centres, domain);
  if (work & work_separation) metrics[M::separation_distance] = separation_distance(centres, domain);

  const auto& spectrum = solver.spectrum();
  out.solve_method = solver.method();

  // The interpolant Pi_n f = sum_i alpha_i k(c_i, .) with G alpha = f(X).
  Eigen::VectorXd alpha, at_points;
  double target_norm_at_centres = 0;  // |f(X)|
  if (work & (work_interpolant | work_residual)) {
    Eigen::VectorXd at_centres(n);
    target.evaluate(centres, std::span<double>(at_centres.data(), static_cast<std::size_t>(n)));
    alpha = solver.solve(at_centres);
    target_norm_at_centres = at_centres.norm();
  }
  if (work & work_residual) {
    at_points.resize(static_cast<Eigen::Index>(point_count));
    target.evaluate(points, std::span<double>(at_points.data(), point_count));
  }

  // The power function from the cross matrix K_mi = k(s_m, c_i), O(n^2) per point, and the
  // residual, in one blocked pass.
  const unsigned grid_work = work & (work_power | work_cardinal | work_residual);
  GridPass pass;
  // The floors from a sample of the points (grid_pass) where neither floor is reported itself.
  const bool sampled =
      sampled_cardinal && (work & work_cardinal) && solver.kept_vectors() == nullptr;
  if (grid_work || cross_out)
    pass =
        grid_pass(kernel, solver, centres, points, grid_work, alpha, at_points, cross_out, sampled);
  if (sampled) cardinal_at_sup_points(kernel, solver, centres, points, pass);
  check_cancelled();
  record_interpolant_metrics(kernel, points, n, spectrum, work, alpha,
                             (work & work_interpolant) ? alpha.dot(gram * alpha) : nan,
                             target_norm_at_centres, pass, out);
  return out;
}
}  // namespace

double solve_round_off(const GramSpectrum& spectrum, Eigen::Index n) {
  const double relative =
      static_cast<double>(n) * eps * spectrum.lambda_max / std::max(spectrum.lambda_min, 0.0);
  return std::isfinite(relative) ? std::min(1.0, relative) : 1.0;
}

Eigen::VectorXd power_function(const AnyKernel& kernel, const GramSolver& solver,
                               std::span<const double> centres, std::span<const double> points) {
  return grid_pass(kernel, solver, centres, points, work_power, {}, {}, nullptr)
      .power_squared.cwiseSqrt();
}

ApproximationMeasurement measure_approximation(const AnyKernel& kernel,
                                               const TargetFunction& target,
                                               std::span<const double> centres,
                                               std::size_t evaluation_points,
                                               const SolverOptions& solver_options,
                                               const MetricSelection& selection) {
  const unsigned work = work_needed<ApproximationMetric>(selection);
  // A compactly supported kernel on the sparse path (sparse_gram.hpp), unless its
  // factorisation cannot decide singularity: then the dense path below decides.
  if (choose_sparse(kernel, kernel.domain().point_count(centres), solver_options, work))
    if (auto sparse = measure_sparse_approximation(kernel, target, centres, evaluation_points,
                                                   solver_options, selection))
      return std::move(*sparse);
  const Eigen::MatrixXd gram = kernel.gram(centres);
  check_cancelled();
  const GramSolver solver(gram, solver_options,
                          work & work_spectrum ? GramSpectrumMode::exact
                                               : GramSpectrumMode::estimate);
  check_cancelled();
  // power_function_floor and error_floor are maxima over every point; where neither is asked
  // for, the floors only size the columns and flags of the other metrics (a sample suffices).
  const bool sampled_cardinal = floors_from_sample(kernel.domain().point_count(centres), selection);
  auto out = measure_interpolant(kernel, target, centres, evaluation_points, gram, solver, work,
                                 nullptr, sampled_cardinal);
  // ||Pi||_{H -> H} of the operator built from the same solver.
  if (work & work_operator_norm) {
    ProjectionOperator op;
    interpolation_operator(kernel, centres, gram, solver, op);
    check_cancelled();
    // Its floor counts the round-off of the weights, which are solves with G.
    out.metrics[ApproximationMetric::projection_operator_norm] = projection_operator_norm(
        kernel, op, &out.floors[ApproximationMetric::projection_operator_norm]);
  }
  keep_selected(selection, out);
  return out;
}

ApproximationMeasurement measure_approximation(const AnyKernel& kernel,
                                               const TargetFunction& target,
                                               std::span<const double> centres,
                                               std::size_t evaluation_points,
                                               const Eigen::MatrixXd& gram,
                                               const GramSolver& solver,
                                               Eigen::MatrixXd* cross_out) {
  constexpr unsigned without_operator = ~(work_projection_residual | work_operator_norm);
  return measure_interpolant(kernel, target, centres, evaluation_points, gram, solver,
                             work_needed<ApproximationMetric>({}) & without_operator, cross_out);
}

}  // namespace rkhs
