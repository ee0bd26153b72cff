// The sparse path of approximation trials (rkhs/approx/sparse_gram.hpp).

#include <dlfcn.h>
#include <fmt/format.h>

#include <Eigen/CholmodSupport>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <vector>

#include "rkhs/approx/cell_grid.hpp"
#include "rkhs/approx/lanczos.hpp"
#include "rkhs/approx/sparse_gram.hpp"
#include "rkhs/core/cancellation.hpp"
#include "rkhs/core/concurrency.hpp"
#include "rkhs/core/work_counters.hpp"

namespace rkhs {

namespace {
constexpr double eps = std::numeric_limits<double>::epsilon();
constexpr double nan = std::numeric_limits<double>::quiet_NaN();
// The extreme eigenvalues a study reports: Lanczos until an eigenvalue lies within this
// relative distance of the Ritz value, in at most this many steps.
constexpr double spectrum_tolerance = 1e-11;
constexpr Eigen::Index spectrum_steps = 500;

// For every cell a of `rows` holding points and every neighbouring cell b of `columns` (the
// same cell geometry) holding points, in increasing order of a, then b, on the calling thread:
// visit(block, row_indices, column_indices, a == b) with block(i, j) = k(row point i, column
// point j). With `upper` (rows and columns the same grid) each pair of cells once, b >= a.
template <class Visit>
void for_each_neighbour_block(const AnyKernel& kernel, const CellGrid& rows,
                              const CellGrid& columns, bool upper, Visit&& visit) {
  const auto d = static_cast<std::size_t>(rows.dimension);
  std::vector<std::size_t> near;
  Eigen::MatrixXd block;
  for (std::size_t a = 0; a < rows.cells(); ++a) {
    const auto first = cell_points(rows, a);
    if (first.empty()) continue;
    cells_around(rows, rows.position(a), 1, near);
    for (const std::size_t b : near) {
      if (upper && b < a) continue;
      const auto second = cell_points(columns, b);
      if (second.empty()) continue;
      block.resize(static_cast<Eigen::Index>(first.size() / d),
                   static_cast<Eigen::Index>(second.size() / d));
      kernel.cross_into(first, second, block);
      visit(block, cell_indices(rows, a), cell_indices(columns, b), a == b);
    }
    check_cancelled();
  }
}

double support_radius(const AnyKernel& kernel) {
  const double radius = kernel.properties().support_radius;
  if (!(radius > 0) || !std::isfinite(radius))
    throw std::invalid_argument(fmt::format(
        "the sparse path needs a kernel of compact support; kernel '{}' has global support",
        kernel.name()));
  return radius;
}

// CHOLMOD's supernodal LL^T through Eigen, with access to the factor for the partial solves
// (P, L^-1, L^-T) the power function needs.
class SparseCholesky
    : public Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> {
 public:
  cholmod_factor* factor() const { return m_cholmodFactor; }
  cholmod_common& common() { return cholmod(); }
};

const char* ordering_name(int ordering) {
  switch (ordering) {
    case CHOLMOD_NATURAL:
      return "natural";
    case CHOLMOD_AMD:
      return "AMD";
    case CHOLMOD_METIS:
      return "METIS";
    case CHOLMOD_NESDIS:
      return "nested dissection";
    case CHOLMOD_COLAMD:
      return "COLAMD";
    default:
      return "CHOLMOD's";
  }
}

// out := A in, with A = P, L^-1 or L^-T (`system`: CHOLMOD_P, CHOLMOD_L, CHOLMOD_Lt), in place
// on the dense columns `x`; `common` is the caller's own (one per block, so blocks may run
// concurrently).
void solve_in_place(int system, cholmod_factor* factor, Eigen::MatrixXd& x,
                    cholmod_common& common) {
  cholmod_dense b = Eigen::viewAsCholmod(x);
  cholmod_dense* result = cholmod_solve(system, factor, &b, &common);
  if (!result) throw std::runtime_error("CHOLMOD's solve failed (out of memory?)");
  std::copy_n(static_cast<const double*>(result->x), x.size(), x.data());
  cholmod_free_dense(&result, &common);
  if (system != CHOLMOD_P) count_sparse_work(0, 0, static_cast<std::uint64_t>(x.cols()));
}

// x with G x = b through the factor (a solve with L and one with L^T).
template <class Factor>
Eigen::VectorXd solve_with(const Factor& cholesky, const Eigen::VectorXd& b) {
  count_sparse_work(0, 0, 2);
  return cholesky.solve(b);
}

}  // namespace

void single_threaded_blas() {
  static std::once_flag once;
  std::call_once(once, [] {
    using SetThreads = void (*)(int);
    if (auto* set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads")))
      set(1);
  });
}

void analyse_one_at_a_time(const std::function<void()>& analyse) {
  static std::mutex one_at_a_time;
  const std::lock_guard lock(one_at_a_time);
  analyse();
}

Eigen::SparseMatrix<double> sparse_gram(const AnyKernel& kernel, std::span<const double> centres) {
  const Domain& domain = kernel.domain();
  const std::size_t n = domain.point_count(centres);
  CellGrid grid = cells_at_least(domain, support_radius(kernel), n);
  bucket(grid, domain, centres);
  // Each pair of cells once: the upper triangle as triplets (reserved for the predicted
  // nonzeros), compressed, then mirrored into both triangles: about 20 bytes a nonzero of G at
  // the peak, not the 50 of mirrored triplets.
  Eigen::SparseMatrix<double> upper(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  {
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(static_cast<std::size_t>(
        0.6 * predicted_gram_nonzeros(kernel.properties(), domain, n) + static_cast<double>(n)));
    for_each_neighbour_block(
        kernel, grid, grid, true,
        [&](const Eigen::MatrixXd& block, std::span<const std::size_t> rows,
            std::span<const std::size_t> cols, bool same_cell) {
          for (Eigen::Index j = 0; j < block.cols(); ++j)
            for (Eigen::Index i = 0; i < (same_cell ? j + 1 : block.rows()); ++i) {
              const double v = block(i, j);
              const auto gi = static_cast<int>(rows[static_cast<std::size_t>(i)]);
              const auto gj = static_cast<int>(cols[static_cast<std::size_t>(j)]);
              if (v == 0 && gi != gj) continue;
              entries.emplace_back(std::min(gi, gj), std::max(gi, gj), v);
            }
        });
    upper.setFromTriplets(entries.begin(), entries.end());
  }
  Eigen::SparseMatrix<double> gram = upper.selfadjointView<Eigen::Upper>();
  upper = Eigen::SparseMatrix<double>();
  count_sparse_work(static_cast<std::uint64_t>(gram.nonZeros()), 0, 0);
  return gram;
}

Eigen::SparseMatrix<double> sparse_cross_columns(const AnyKernel& kernel,
                                                 std::span<const double> points,
                                                 std::span<const double> centres) {
  const Domain& domain = kernel.domain();
  const std::size_t n = domain.point_count(centres), m = domain.point_count(points);
  CellGrid centre_grid = cells_at_least(domain, support_radius(kernel), n);
  CellGrid point_grid = centre_grid;
  bucket(centre_grid, domain, centres);
  bucket(point_grid, domain, points);
  std::vector<Eigen::Triplet<double>> entries;
  // Row i of a block is a point, column j a centre: the entry (centre, point) of the result.
  for_each_neighbour_block(kernel, point_grid, centre_grid, false,
                           [&](const Eigen::MatrixXd& block, std::span<const std::size_t> at,
                               std::span<const std::size_t> sources, bool) {
                             for (Eigen::Index j = 0; j < block.cols(); ++j)
                               for (Eigen::Index i = 0; i < block.rows(); ++i)
                                 if (const double v = block(i, j); v != 0)
                                   entries.emplace_back(
                                       static_cast<int>(sources[static_cast<std::size_t>(j)]),
                                       static_cast<int>(at[static_cast<std::size_t>(i)]), v);
                           });
  Eigen::SparseMatrix<double> cross(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(m));
  cross.setFromTriplets(entries.begin(), entries.end());
  count_sparse_work(static_cast<std::uint64_t>(cross.nonZeros()), 0, 0);
  return cross;
}

double analysed_factor_nonzeros(const Eigen::SparseMatrix<double>& gram) {
  SparseCholesky cholesky;
  cholesky.common().print = 0;
  analyse_one_at_a_time([&] { cholesky.analyzePattern(gram); });
  return cholesky.common().lnz;
}

bool floors_from_sample(std::size_t n, const MetricSelection& selection) {
  const auto asked = [&](ApproximationMetric metric) {
    const auto i = static_cast<std::size_t>(metric);
    return selection.empty() || (i < selection.size() && selection[i]);
  };
  return n >= sampled_floor_min_centres && !asked(ApproximationMetric::power_function_floor) &&
         !asked(ApproximationMetric::error_floor);
}

bool choose_sparse(const AnyKernel& kernel, std::size_t n, const SolverOptions& options,
                   unsigned work) {
  if (options.algebra == GramAlgebra::dense) return false;
  const bool compact = kernel.properties().support_radius > 0;
  const bool dense_only = work & work_operator_norm;
  if (options.algebra == GramAlgebra::sparse) {
    support_radius(kernel);  // throws for global support
    if (dense_only)
      throw std::invalid_argument(
          "[linear_algebra] solver = \"sparse\" does not compute projection_operator_norm "
          "(the dense interpolation operator): leave it out of study.metrics, or take solver = "
          "\"auto\" or \"dense\"");
    return true;
  }
  if (!compact || dense_only) return false;
  const double count = static_cast<double>(n);
  return predicted_gram_nonzeros(kernel.properties(), kernel.domain(), n) <= 0.25 * count * count;
}

namespace {

// On the dense columns `columns` (k_X(s) of some points): quadratic := |L^-1 P k_X(s)|^2 and,
// when `norms` is given, norms := |G^-1 k_X(s)|^2, each column by itself (a CHOLMOD common of
// its own, so that blocks may run concurrently).
void solve_columns(cholmod_factor* factor, Eigen::MatrixXd& columns,
                   Eigen::Ref<Eigen::VectorXd> quadratic, Eigen::VectorXd* norms) {
  cholmod_common common;
  cholmod_start(&common);
  solve_in_place(CHOLMOD_P, factor, columns, common);
  solve_in_place(CHOLMOD_L, factor, columns, common);
  quadratic = columns.colwise().squaredNorm().transpose();
  if (norms) {
    solve_in_place(CHOLMOD_Lt, factor, columns, common);
    *norms = columns.colwise().squaredNorm().transpose();
  }
  cholmod_finish(&common);
}

// The pass of floors_from_sample (on the sparse path): the points bounded_power_sup solves for the
// sup (with `search`), and the floors' sample: 64 points spread over the grid and, with a
// `residual`, the point that sets sup_error.
BoundedPowerSup bounded_pass(const AnyKernel& kernel, std::span<const double> centres,
                             std::span<const double> points, cholmod_factor* factor,
                             const Eigen::VectorXd* residual, bool search) {
  const auto d = static_cast<std::size_t>(kernel.domain().dimension);
  const std::size_t point_count = kernel.domain().point_count(points);
  std::vector<std::size_t> sample;
  for (std::size_t k = 0; k < 64; ++k) sample.push_back(k * (point_count - 1) / 63);
  if (residual) {
    Eigen::Index worst = 0;
    residual->cwiseAbs().maxCoeff(&worst);
    sample.push_back(static_cast<std::size_t>(worst));
  }
  const ExactPowerBlock exact = [&](std::span<const std::size_t> which,
                                    Eigen::Ref<Eigen::VectorXd> power_squared,
                                    Eigen::Ref<Eigen::VectorXd> norms_out) {
    std::vector<double> at(which.size() * d);
    for (std::size_t k = 0; k < which.size(); ++k)
      std::copy_n(&points[which[k] * d], d, &at[k * d]);
    Eigen::MatrixXd columns = Eigen::MatrixXd(sparse_cross_columns(kernel, at, centres));
    Eigen::VectorXd quadratic(columns.cols()), norms;
    solve_columns(factor, columns, quadratic, &norms);
    power_squared = (kernel.diagonal(at) - quadratic).cwiseMax(0.0);
    norms_out = norms;
  };
  return bounded_power_sup(kernel, centres, points, sample, exact, search);
}

}  // namespace

std::optional<ApproximationMeasurement> measure_sparse_approximation(
    const AnyKernel& kernel, const TargetFunction& target, std::span<const double> centres,
    std::size_t evaluation_points, const SolverOptions& options, const MetricSelection& selection) {
  (void)options;
  single_threaded_blas();
  unsigned work = work_needed<ApproximationMetric>(selection);
  if (work & work_projection_residual) work |= work_power;
  const Domain& domain = kernel.domain();
  const auto n = static_cast<Eigen::Index>(domain.point_count(centres));
  using M = ApproximationMetric;

  const Eigen::SparseMatrix<double> gram = sparse_gram(kernel, centres);
  check_cancelled();
  SparseCholesky cholesky;
  cholesky.common().print = 0;  // a matrix that is not positive definite is answered below
  cholesky.common().quick_return_if_not_posdef = 1;
  analyse_one_at_a_time([&] { cholesky.analyzePattern(gram); });
  const cholmod_common& analysed = cholesky.common();
  const int ordering = analysed.method[analysed.selected].ordering;
  const double factor_nonzeros = analysed.lnz;
  cholesky.factorize(gram);
  count_factorisation();
  count_sparse_work(0, static_cast<std::uint64_t>(factor_nonzeros), 0);
  check_cancelled();
  if (cholesky.info() != Eigen::Success) return std::nullopt;  // not positive definite

  // The extreme eigenvalues: as GramSolver's estimate mode finds them, or resolved to
  // spectrum_tolerance when the study reports them (Lanczos on G and on G^-1 through the factor).
  GramSpectrum spectrum;
  {
    const auto by_gram = [&](const auto& in, Eigen::VectorXd& out) { out.noalias() = gram * in; };
    const auto by_inverse = [&](const auto& in, Eigen::VectorXd& out) {
      out = solve_with(cholesky, Eigen::VectorXd(in));
    };
    double lambda_max = 0, inverse_max = 0;
    if (work & work_spectrum) {
      const auto largest = lanczos_largest_resolved(by_gram, n, spectrum_tolerance, spectrum_steps);
      const auto inverse =
          lanczos_largest_resolved(by_inverse, n, spectrum_tolerance, spectrum_steps);
      if (!largest || !inverse) return std::nullopt;  // not resolved: the dense path's exact solve
      lambda_max = *largest;
      inverse_max = *inverse;
    } else {
      lambda_max = lanczos_largest(by_gram, n, 1e-13, 80);
      inverse_max = lanczos_largest(by_inverse, n, 1e-4, 40);
    }
    const double lambda_min = 1.0 / inverse_max;
    if (!(lambda_min > 100.0 * static_cast<double>(n) * eps * lambda_max)) return std::nullopt;
    spectrum = {lambda_min, lambda_max, lambda_max / lambda_min, false, !(work & work_spectrum)};
  }

  ApproximationMeasurement out;
  auto& metrics = out.metrics;
  out.solve_method = fmt::format(
      "sparse Cholesky (CHOLMOD {}.{}.{} supernodal, {} ordering; {} nonzeros in G, {:.0f} in L)",
      CHOLMOD_MAIN_VERSION, CHOLMOD_SUB_VERSION, CHOLMOD_SUBSUB_VERSION, ordering_name(ordering),
      gram.nonZeros(), factor_nonzeros);
  if (work & work_fill) metrics[M::fill_distance] = fill_distance(centres, domain);
  if (work & work_separation)
    metrics[M::separation_distance] = separation_distance(centres, domain);

  const auto points = domain.uniform_points(evaluation_points);
  const std::size_t point_count = domain.point_count(points);
  Eigen::VectorXd alpha, at_points;
  double target_norm_at_centres = 0;
  if (work & (work_interpolant | work_residual)) {
    Eigen::VectorXd at_centres(n);
    target.evaluate(centres, std::span<double>(at_centres.data(), static_cast<std::size_t>(n)));
    alpha = solve_with(cholesky, at_centres);
    target_norm_at_centres = at_centres.norm();
  }
  if (work & work_residual) {
    at_points.resize(static_cast<Eigen::Index>(point_count));
    target.evaluate(points, std::span<double>(at_points.data(), point_count));
  }

  // The evaluation points in chunks of at most about 2^23 cross-matrix entries (memory O(n x
  // block), never n x M): each chunk's sparse cross columns give its residual and, on the full
  // pass, its blocks of columns densified, permuted and solved with L (and L^T for the floors),
  // each block by itself. Where the floors may come from a sample, the power function's sup
  // comes from bounded_power_sup instead, which solves for a few points only.
  const bool power = work & (work_power | work_cardinal), cardinal = work & work_cardinal;
  const bool residual_wanted = work & work_residual;
  const bool bounded = power && floors_from_sample(static_cast<std::size_t>(n), selection);
  const auto m_total = static_cast<Eigen::Index>(point_count);
  const auto d = static_cast<std::size_t>(domain.dimension);
  Eigen::VectorXd quadratic, solution_norm_squared, residual;
  if ((power && !bounded) || residual_wanted) {
    if (power && !bounded) quadratic.resize(m_total);
    if (cardinal && !bounded) solution_norm_squared.resize(m_total);
    if (residual_wanted) residual.resize(m_total);
    // At most about 32 MB of dense columns per block.
    const Eigen::Index per_block =
        std::clamp<Eigen::Index>((Eigen::Index{1} << 22) / std::max<Eigen::Index>(n, 1), 16, 512);
    const double per_point = static_cast<double>(gram.nonZeros()) / static_cast<double>(n);
    const Eigen::Index per_chunk =
        per_block * std::max<Eigen::Index>(
                        1, static_cast<Eigen::Index>(std::ldexp(1.0, 23) / per_point / per_block));
    for (Eigen::Index chunk = 0; chunk < m_total; chunk += per_chunk) {
      const Eigen::Index in_chunk = std::min(per_chunk, m_total - chunk);
      const Eigen::SparseMatrix<double> cross = sparse_cross_columns(
          kernel,
          std::span<const double>(points).subspan(static_cast<std::size_t>(chunk) * d,
                                                  static_cast<std::size_t>(in_chunk) * d),
          centres);
      check_cancelled();
      if (residual_wanted)
        residual.segment(chunk, in_chunk) =
            at_points.segment(chunk, in_chunk) - cross.transpose() * alpha;
      if (!power || bounded) continue;
      const auto blocks = static_cast<std::size_t>((in_chunk + per_block - 1) / per_block);
      run_parts(blocks, [&](std::size_t b) {
        const Eigen::Index first = static_cast<Eigen::Index>(b) * per_block;
        const Eigen::Index count = std::min(per_block, in_chunk - first);
        Eigen::MatrixXd columns = Eigen::MatrixXd(cross.middleCols(first, count));
        Eigen::VectorXd norms;
        solve_columns(cholesky.factor(), columns, quadratic.segment(chunk + first, count),
                      cardinal ? &norms : nullptr);
        if (cardinal) solution_norm_squared.segment(chunk + first, count) = norms;
        check_cancelled();
      });
    }
  }

  GridPass pass;
  if (bounded) {
    const bool search = work & work_power;
    BoundedPowerSup sup = bounded_pass(kernel, centres, points, cholesky.factor(),
                                       residual_wanted ? &residual : nullptr, search);
    if (search)
      out.solve_method +=
          fmt::format("; the power function's sup from local bounds: {} of {} points solved",
                      sup.evaluated.size(), point_count);
    pass.power_squared = std::move(sup.power_squared);
    pass.solution_norm_squared = std::move(sup.solution_norm_squared);
  } else {
    if (power) pass.power_squared = (kernel.diagonal(points) - quadratic).cwiseMax(0.0);
    pass.solution_norm_squared = std::move(solution_norm_squared);
  }
  pass.residual = std::move(residual);
  record_interpolant_metrics(kernel, points, n, spectrum, work, alpha,
                             (work & work_interpolant) ? alpha.dot(gram * alpha) : nan,
                             target_norm_at_centres, pass, out);
  keep_selected(selection, out);
  return out;
}

}  // namespace rkhs
