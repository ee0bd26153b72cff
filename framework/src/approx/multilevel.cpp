// Multilevel interpolation with a compactly supported kernel (rkhs/approx/multilevel.hpp).
#include "rkhs/approx/multilevel.hpp"

#include <fmt/format.h>

#include <Eigen/CholmodSupport>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <stdexcept>

#include "rkhs/approx/lanczos.hpp"
#include "rkhs/approx/sparse_gram.hpp"
#include "rkhs/core/cancellation.hpp"
#include "rkhs/core/concurrency.hpp"
#include "rkhs/core/work_counters.hpp"

namespace rkhs {

namespace {
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Points per chunk of a residual update: a chunk's sparse cross matrix holds about
// chunk x (centres within rho) entries, and each chunk buckets the level's centres once.
constexpr std::size_t points_per_chunk = 32768;

// residual(m) -= s(points_m), s = sum_i alpha_i k(c_i, .), by chunks of points on idle threads.
void subtract_interpolant(const AnyKernel& kernel, std::span<const double> centres,
                          const Eigen::VectorXd& alpha, std::span<const double> points,
                          Eigen::VectorXd& residual) {
  const auto d = static_cast<std::size_t>(kernel.domain().dimension);
  const std::size_t count = points.size() / d;
  const std::size_t chunks = (count + points_per_chunk - 1) / points_per_chunk;
  run_parts(chunks, [&](std::size_t c) {
    const std::size_t first = c * points_per_chunk;
    const std::size_t size = std::min(points_per_chunk, count - first);
    const Eigen::SparseMatrix<double> cross =
        sparse_cross_columns(kernel, points.subspan(first * d, size * d), centres);
    residual.segment(static_cast<Eigen::Index>(first), static_cast<Eigen::Index>(size)) -=
        cross.transpose() * alpha;
    check_cancelled();
  });
}

// The indices in X_J of the points of X_j (both tensor grids, axis 1 fastest).
std::vector<std::size_t> nested_indices(const Domain& domain, std::int64_t m0, int level,
                                        int finest) {
  const int d = domain.dimension;
  const std::size_t m = multilevel_points_per_axis(domain, m0, level);
  const std::size_t m_fine = multilevel_points_per_axis(domain, m0, finest);
  const std::size_t step = std::size_t{1} << (finest - level);
  std::size_t count = 1;
  for (int a = 0; a < d; ++a) count *= m;
  std::vector<std::size_t> out(count);
  for (std::size_t p = 0; p < count; ++p) {
    std::size_t rest = p, index = 0, stride = 1;
    for (int a = 0; a < d; ++a) {
      index += (rest % m) * step * stride;
      rest /= m;
      stride *= m_fine;
    }
    out[p] = index;
  }
  return out;
}

double largest_spacing(const Domain& domain, std::int64_t m0, int level) {
  double h = 0;
  for (int a = 0; a < domain.dimension; ++a)
    h = std::max(h, domain.extent(a) / static_cast<double>(m0 << level));
  return h;
}
}  // namespace

std::size_t multilevel_points_per_axis(const Domain& domain, std::int64_t m0, int level) {
  return static_cast<std::size_t>(m0 << level) + (domain.periodic ? 0 : 1);
}

std::size_t multilevel_centre_count(const Domain& domain, std::int64_t m0, int level) {
  const std::size_t m = multilevel_points_per_axis(domain, m0, level);
  std::size_t count = 1;
  for (int a = 0; a < domain.dimension; ++a) count *= m;
  return count;
}

int multilevel_level_of(const Domain& domain, std::int64_t m0, std::size_t n) {
  for (int j = 0; j <= 24; ++j) {
    const std::size_t count = multilevel_centre_count(domain, m0, j);
    if (count == n) return j;
    if (count > n) break;
  }
  return -1;
}

std::unique_ptr<AnyKernel> kernel_with_radius(const AnyKernel& kernel, double radius) {
  const auto* entry = kernel_registry().find(kernel.name());
  if (!entry) throw std::invalid_argument(fmt::format("unknown kernel '{}'", kernel.name()));
  std::map<std::string, ParameterValue> given;
  bool has_radius = false;
  for (const auto& [name, value] : kernel.parameters().values()) {
    if (name == "radius") {
      has_radius = true;
      given.emplace(name, radius);
    } else {
      given.emplace(name, value);
    }
  }
  if (!has_radius || !(kernel.properties().support_radius > 0))
    throw std::invalid_argument(fmt::format(
        "multilevel interpolation needs a kernel of compact support with a parameter 'radius' "
        "(its support radius, scaled per level), such as wendland; kernel '{}' is not one",
        kernel.name()));
  return make_kernel(
      kernel.name(),
      ParameterSet::resolve(entry->info.parameters, given,
                            entry->info.user_parameters ? &*entry->info.user_parameters : nullptr),
      kernel.domain());
}

ProjectionFootprint predict_multilevel(const AnyKernel& kernel, const MultilevelSettings& settings,
                                       int finest_level, std::size_t evaluation_points) {
  const Domain& domain = kernel.domain();
  const auto d = static_cast<double>(domain.dimension);
  const auto points = static_cast<double>(evaluation_points);
  const auto fine = static_cast<double>(multilevel_centre_count(domain, settings.m0, finest_level));
  ProjectionFootprint out;
  double largest_level = 0;  // bytes
  for (int j = 0; j <= finest_level; ++j) {
    const std::size_t n = multilevel_centre_count(domain, settings.m0, j);
    const auto level_kernel =
        kernel_with_radius(kernel, settings.nu * largest_spacing(domain, settings.m0, j));
    const auto factor = predict_sparse_factor(level_kernel->properties(), domain, n);
    // Bytes as sparse_trial_megabytes (trial_cost.cpp) counts them: at most 20 a nonzero of G
    // while it is assembled, then 12 a stored nonzero of G, 6 of CHOLMOD's copy of its upper
    // triangle and 10 a nonzero of the supernodal factor; a chunk's cross matrix holds
    // (nonzeros of G / n) entries a point, 56 bytes each with its assembly, on two threads.
    const double per_point = factor.gram_nonzeros / static_cast<double>(n);
    const double chunks = 2.0 * 56.0 * per_point *
                          std::min(static_cast<double>(points_per_chunk), std::max(points, fine));
    largest_level = std::max(largest_level,
                             std::max(20.0 * factor.gram_nonzeros,
                                      18.0 * factor.gram_nonzeros + 10.0 * factor.factor_nonzeros) +
                                 chunks);
    out.gram_nonzeros += factor.gram_nonzeros;
    out.factor_nonzeros += factor.factor_nonzeros;
    // The factorisation, one solve, and the residual updates on X_J and the evaluation points.
    out.flops +=
        factor.factor_flops + 4.0 * factor.factor_nonzeros + 2.0 * per_point * (fine + points);
  }
  const double vectors = 8.0 * ((d + 1.0) * fine + (d + 1.0) * points);
  out.megabytes = (largest_level + vectors) / 1048576.0 + 64.0;
  return out;
}

MultilevelResult multilevel_interpolation(const AnyKernel& kernel, const TargetFunction& target,
                                          const MultilevelSettings& settings, int finest_level,
                                          std::span<const double> points, bool spectra) {
  single_threaded_blas();
  const Domain& domain = kernel.domain();
  const auto d = static_cast<std::size_t>(domain.dimension);
  const std::size_t point_count = points.size() / d;
  MultilevelResult out;
  out.finest_centres =
      domain.uniform_points(multilevel_centre_count(domain, settings.m0, finest_level));
  const std::size_t fine_count = out.finest_centres.size() / d;
  out.finest_residual.resize(static_cast<Eigen::Index>(fine_count));
  target.evaluate(out.finest_centres, std::span<double>(out.finest_residual.data(), fine_count));
  out.residual.resize(static_cast<Eigen::Index>(point_count));
  target.evaluate(points, std::span<double>(out.residual.data(), point_count));
  out.target_l2 = domain.l2_norm(std::span<const double>(out.residual.data(), point_count));
  out.target_sup = point_count > 0 ? out.residual.cwiseAbs().maxCoeff() : 0.0;

  for (int j = 0; j <= finest_level; ++j) {
    MultilevelLevel level;
    auto start = Clock::now();
    const auto centres = domain.uniform_points(multilevel_centre_count(domain, settings.m0, j));
    level.centres = centres.size() / d;
    level.spacing = largest_spacing(domain, settings.m0, j);
    level.radius = settings.nu * level.spacing;
    const auto level_kernel = kernel_with_radius(kernel, level.radius);
    const auto indices = nested_indices(domain, settings.m0, j, finest_level);
    Eigen::VectorXd values(static_cast<Eigen::Index>(indices.size()));
    for (std::size_t i = 0; i < indices.size(); ++i)
      values[static_cast<Eigen::Index>(i)] =
          out.finest_residual[static_cast<Eigen::Index>(indices[i])];

    const Eigen::SparseMatrix<double> gram = sparse_gram(*level_kernel, centres);
    level.nonzeros = static_cast<std::size_t>(gram.nonZeros());
    check_cancelled();
    Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> cholesky;
    cholesky.cholmod().print = 0;
    cholesky.cholmod().quick_return_if_not_posdef = 1;
    analyse_one_at_a_time([&] { cholesky.analyzePattern(gram); });
    cholesky.factorize(gram);
    if (cholesky.info() != Eigen::Success)
      throw std::runtime_error(fmt::format(
          "multilevel level {}: the Gram matrix of {} centres (radius {}) is not positive "
          "definite to working precision for CHOLMOD",
          j, level.centres, level.radius));
    level.factor_nonzeros = static_cast<std::size_t>(cholesky.cholmod().lnz);
    count_factorisation();
    count_sparse_work(0, static_cast<std::uint64_t>(level.factor_nonzeros), 2);
    const Eigen::VectorXd alpha = cholesky.solve(values);
    check_cancelled();
    if (spectra && j == finest_level) {
      const auto n = static_cast<Eigen::Index>(level.centres);
      const auto largest = lanczos_largest_resolved(
          [&](const auto& in, Eigen::VectorXd& result) { result.noalias() = gram * in; }, n,
          multilevel_spectrum_tolerance, 300);
      const auto inverse = lanczos_largest_resolved(
          [&](const auto& in, Eigen::VectorXd& result) {
            count_sparse_work(0, 0, 2);
            result = cholesky.solve(Eigen::VectorXd(in));
          },
          n, multilevel_spectrum_tolerance, 300);
      if (largest && inverse) {
        level.lambda_max = *largest;
        level.lambda_min = 1.0 / *inverse;
      }
    }
    level.factor_seconds = seconds_since(start);

    start = Clock::now();
    subtract_interpolant(*level_kernel, centres, alpha, out.finest_centres, out.finest_residual);
    subtract_interpolant(*level_kernel, centres, alpha, points, out.residual);
    level.l2_error = domain.l2_norm(std::span<const double>(out.residual.data(), point_count));
    level.sup_error = out.residual.cwiseAbs().maxCoeff();
    level.evaluation_seconds = seconds_since(start);
    out.levels.push_back(level);
  }
  return out;
}

}  // namespace rkhs
