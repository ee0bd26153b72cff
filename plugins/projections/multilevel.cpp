// The multilevel (multiscale) interpolation with a compactly supported kernel
// (docs/projections.md, "multilevel"; rkhs/approx/multilevel.hpp): s = s_0 + ... + s_j, s_l the
// interpolant of the residual of levels 0 .. l-1 on the level-l grid with the support radius
// nu h_l. Matrix-free (projection.hpp): its levels are sparse Gram matrices factorised by
// CHOLMOD, and it measures its trials itself.
#include "rkhs/approx/multilevel.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

#include "rkhs/approx/projection.hpp"

namespace rkhs {
namespace {

class Multilevel final : public Projection {
 public:
  static PluginInfo info() {
    return {"multilevel",
            "multilevel interpolation of a compactly supported kernel (Wendland): nested grids "
            "of m0 2^j + 1 points per axis, support radius nu h_j on level j, each level "
            "interpolating the residual of the coarser ones; n is the finest level's centre "
            "count; sparse Gram matrices (CHOLMOD), matrix-free",
            {integer_parameter("m0", 4, "intervals per axis of level 0", 1, 1024),
             positive_parameter("nu", 4.0, "support radius over grid spacing, rho_j = nu h_j")},
            {}};
  }
  explicit Multilevel(const ParameterSet& p) : settings_{p.integer("m0"), p.real("nu")} {}

  ProjectionProperties properties() const override {
    using M = ApproximationMetric;
    ProjectionProperties p;
    p.resolution = ProjectionResolution::level;
    p.matrix_free = true;
    p.kernel_scaled_with_level = true;
    for (const auto m : {M::fill_distance, M::separation_distance, M::l2_error, M::sup_error,
                         M::level_reduction_factor, M::level_condition_number, M::level_nonzeros})
      p.measures |= measured_metric_bit(m);
    return p;
  }

  void check(const AnyKernel& kernel, std::size_t n) const override {
    level_of(kernel, n);
    kernel_with_radius(kernel, settings_.nu);  // a compactly supported kernel with a radius
  }

  std::optional<ProjectionFootprint> footprint(const AnyKernel& kernel, std::size_t n,
                                               std::size_t evaluation_points) const override {
    check(kernel, n);
    return predict_multilevel(kernel, settings_, level_of(kernel, n), evaluation_points);
  }

  void build(const ProjectionRequest&, ProjectionOperator&) const override {
    throw std::invalid_argument("projection 'multilevel' is matrix-free: it has no operator");
  }

  void measure(const ProjectionTrial& trial, ProjectionMeasurement& out) const override {
    using M = ApproximationMetric;
    const Domain& domain = trial.kernel.domain();
    const int level = level_of(trial.kernel, trial.n);
    const auto result = multilevel_interpolation(trial.kernel, trial.target, settings_, level,
                                                 trial.points, trial.work & work_level_spectrum);
    const auto& finest = result.levels.back();
    // The tensor grid's fill distance is half a cell's diagonal, its separation half the
    // smallest spacing.
    double diagonal = 0, smallest = INFINITY;
    for (int a = 0; a < domain.dimension; ++a) {
      const double h = domain.extent(a) / static_cast<double>(settings_.m0 << level);
      diagonal += h * h;
      smallest = std::min(smallest, h);
    }
    out.metrics[M::fill_distance] = 0.5 * std::sqrt(diagonal);
    out.metrics[M::separation_distance] = 0.5 * smallest;
    const double previous = result.levels.size() > 1
                                ? result.levels[result.levels.size() - 2].l2_error
                                : result.target_l2;
    // Round-off of a level's L2 error, at the scale of the target: n_l eps ||f||, the n eps
    // of a solve with a Gram matrix whose entries are at most 1 (a Wendland function); the sup
    // error's likewise with max |f| (the last digits of both follow the BLAS kernels CHOLMOD
    // runs, which differ between processors); the reduction factor's floor propagated from the
    // two errors' to first order (e_{-1} = f has none).
    const auto error_floor = [&](const MultilevelLevel& l) {
      return static_cast<double>(l.centres) * std::numeric_limits<double>::epsilon() *
             result.target_l2;
    };
    const double factor = finest.l2_error / previous;
    out.metrics[M::l2_error] = finest.l2_error;
    out.floors[M::l2_error] = error_floor(finest);
    if (finest.l2_error <= out.floors[M::l2_error]) out.add_flag("l2_error_at_floor");
    out.metrics[M::sup_error] = finest.sup_error;
    out.floors[M::sup_error] = static_cast<double>(finest.centres) *
                               std::numeric_limits<double>::epsilon() * result.target_sup;
    if (finest.sup_error <= out.floors[M::sup_error]) out.add_flag("sup_error_at_floor");
    out.metrics[M::level_reduction_factor] = factor;
    out.floors[M::level_reduction_factor] =
        factor *
        (error_floor(finest) / finest.l2_error +
         (result.levels.size() > 1 ? error_floor(result.levels[result.levels.size() - 2]) / previous
                                   : 0.0));
    // The condition number's floor: Weyl's perturbation n eps lambda_max of each eigenvalue
    // (as the Gram spectrum's) and the Lanczos estimates' tolerance, relative to each.
    const double condition = finest.lambda_max / finest.lambda_min;
    out.metrics[M::level_condition_number] = condition;
    out.floors[M::level_condition_number] =
        condition * (static_cast<double>(finest.centres) * std::numeric_limits<double>::epsilon() *
                         finest.lambda_max / finest.lambda_min +
                     2 * multilevel_spectrum_tolerance);
    out.metrics[M::level_nonzeros] = static_cast<double>(finest.nonzeros);
    out.set_solve_method(fmt::format(
        "multilevel interpolation, levels 0..{} (nu = {}, m0 = {}), sparse Cholesky (CHOLMOD "
        "supernodal) per level; finest level: {} centres, radius {:.6g}, {} nonzeros in G, "
        "{} in L",
        level, settings_.nu, settings_.m0, finest.centres, finest.radius, finest.nonzeros,
        finest.factor_nonzeros));
  }

 private:
  int level_of(const AnyKernel& kernel, std::size_t n) const {
    const Domain& domain = kernel.domain();
    const int level = multilevel_level_of(domain, settings_.m0, n);
    if (level >= 0) return level;
    std::string valid;
    for (int j = 0; j <= 9; ++j)
      valid += fmt::format("{}{}", j ? ", " : "", multilevel_centre_count(domain, settings_.m0, j));
    throw std::invalid_argument(fmt::format(
        "projection 'multilevel': n = {} is not the centre count (m0 2^j{})^d of a level j "
        "with m0 = {}, d = {}; the levels j = 0..9 have n = {}",
        n, domain.periodic ? "" : " + 1", settings_.m0, domain.dimension, valid));
  }

  MultilevelSettings settings_;
};

}  // namespace
}  // namespace rkhs

RKHS_REGISTER_PROJECTION(rkhs::Multilevel)
