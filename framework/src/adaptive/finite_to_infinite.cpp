#include "rkhs/adaptive/finite_to_infinite.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "rkhs/adaptive/breakpoints.hpp"
#include "rkhs/adaptive/learning_map.hpp"
#include "rkhs/adaptive/lyapunov.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/adaptive/reference_resolution.hpp"
#include "rkhs/core/cancellation.hpp"
#include "rkhs/kernel/mapped_basis.hpp"

namespace rkhs {

namespace {

// Features at points as a dense points x F matrix (F = feature_count()).
Eigen::MatrixXd feature_values(const KernelBasis& features, std::span<const double> points) {
  Eigen::MatrixXd out(static_cast<Eigen::Index>(points.size()),
                      static_cast<Eigen::Index>(features.size()));
  Eigen::VectorXd row(out.cols());
  for (std::size_t m = 0; m < points.size(); ++m) {
    features.evaluate(points[m], row.data());
    out.row(static_cast<Eigen::Index>(m)) = row.transpose();
  }
  return out;
}

// R = L^T W, with G_B = L L^T: row i holds the weights of the i-th function of an orthonormal
// basis of H_j = range(Pi_j) over the projection's samples (dim x |S|).
Eigen::MatrixXd orthonormal_basis_weights(const AnyKernel& kernel, const ProjectionOperator& op) {
  const Eigen::MatrixXd basis_gram = projection_basis_gram(kernel, op);
  const Eigen::LLT<Eigen::MatrixXd> cholesky(basis_gram);
  const double largest = basis_gram.diagonal().cwiseAbs().maxCoeff();
  if (cholesky.info() != Eigen::Success ||
      cholesky.matrixL().toDenseMatrix().diagonal().minCoeff() <= 1e-7 * std::sqrt(largest))
    throw std::invalid_argument(
        "the projection's basis is linearly dependent in H (its Gram matrix G_B is singular to "
        "working precision): no coordinates for H_j");
  const Eigen::MatrixXd L = cholesky.matrixL();
  return L.transpose() * op.weights();
}

// The difference fhat - Pi_j^* fhat_j as coefficients c = U beta - V a over functions whose
// H-Gram matrix is `metric` and whose values on the grid are the rows of `on_grid`:
//   exact features: the features themselves, U = I, V = Phi_S^T R^T, metric I (both in the
//     range of the features);
//   a reference resolution H_N: the sections at C and at S, U = [L^-T; 0], V = [0; R^T],
//     metric the Gram matrix of C and S together.
struct GapCoordinates {
  const ReferenceResolvedKernel* resolved = nullptr;  ///< the reference resolution, if any
  Eigen::MatrixXd U, V, metric, on_grid;

  // c for the infinite estimator's coefficients beta and the finite one's a.
  void gap(const Eigen::Ref<const Eigen::VectorXd>& beta,
           const Eigen::Ref<const Eigen::VectorXd>& a, Eigen::VectorXd& c) const {
    if (resolved)
      c.noalias() = U * beta;
    else
      c = beta;
    c.noalias() -= V * a;
  }
  // ||c||_H.
  double norm_H(const Eigen::VectorXd& c) const {
    return resolved ? std::sqrt(std::max(0.0, c.dot(metric * c))) : c.norm();
  }
};

GapCoordinates gap_coordinates(const AnyKernel& kernel, const KernelBasis& features,
                               const ProjectionOperator& op, const Eigen::MatrixXd& R,
                               const std::vector<double>& grid) {
  GapCoordinates out;
  const auto F = static_cast<Eigen::Index>(features.size());
  out.resolved = dynamic_cast<const ReferenceResolvedKernel*>(&kernel);
  if (const auto* resolved = out.resolved) {
    std::vector<double> points = resolved->centres();
    const auto N = static_cast<Eigen::Index>(points.size());
    points.insert(points.end(), op.samples().begin(), op.samples().end());
    const auto all = static_cast<Eigen::Index>(points.size());
    out.U = Eigen::MatrixXd::Zero(all, F);
    out.U.topRows(N) = resolved->inverse_factor().transpose();
    out.V = Eigen::MatrixXd::Zero(all, R.rows());
    out.V.bottomRows(all - N) = R.transpose();
    out.metric = resolved->kernel().gram(points);
    out.on_grid = resolved->kernel().cross(grid, points);
  } else {
    out.V = feature_values(features, op.samples()).transpose() * R.transpose();  // F x dim
    out.on_grid = feature_values(features, grid);                                // M x F
  }
  return out;
}

}  // namespace

EstimateGaps measure_estimate_gaps(const AnyKernel& kernel, const TargetFunction& target,
                                   const ProjectionOperator& op, const Plant& plant,
                                   const LearningLaw& law, const Integrator& integrator,
                                   const AdaptiveSettings& settings,
                                   std::size_t evaluation_points) {
  if (kernel.feature_count() == 0)
    throw std::invalid_argument(fmt::format(
        "the infinite-dimensional estimator needs a kernel with a finite feature map; kernel '{}' "
        "has none",
        kernel.name()));
  if (settings.limit())
    throw std::invalid_argument(
        "the estimate gaps are taken along the integration: laps = \"limit\" has none");
  const Domain& domain = kernel.domain();
  const double gamma = law.gain();
  EstimateGaps out;

  const Eigen::MatrixXd R = orthonormal_basis_weights(kernel, op);  // dim x |S|
  const auto dimension = R.rows();
  out.dimension = static_cast<std::size_t>(dimension);

  const auto features = kernel.feature_basis();
  const auto F = static_cast<Eigen::Index>(features->size());
  const auto grid = domain.uniform_points(evaluation_points);
  const GapCoordinates coordinates = gap_coordinates(kernel, *features, op, R, grid);
  const Eigen::MatrixXd& V = coordinates.V;
  const Eigen::MatrixXd& on_grid = coordinates.on_grid;

  const Eigen::MatrixXd& A = plant.A();
  const Eigen::VectorXd& B = plant.B();
  const Eigen::Index d = A.rows();
  const Eigen::MatrixXd P = solve_lyapunov(A, settings.q.for_dimension(d)).P;
  const std::function<double(double)> road = [&](double s) { return target(s); };
  const std::function<double(double)> road_slope = [&](double s) { return target.slope(s); };

  // The two systems: features with Gamma^-1 I (rkhs_embedding), r(s) with Gamma^-1 I.
  const LearningMap infinite_map = LearningMap::scalar(F, 1.0 / gamma);
  const LearningMap finite_map = LearningMap::scalar(dimension, 1.0 / gamma);
  // r(s) = R k(S, s): the coordinates of Pi_j k(s, .) in the orthonormal basis of H_j.
  MappedBasis sections([&] { return kernel.basis(op.samples()); }, R);
  AdaptiveSystem infinite(A, B, P, *features, infinite_map, road, road_slope, domain,
                          settings.speed, AdaptiveSystem::LearningSignal::from_phi);
  AdaptiveSystem finite(A, B, P, sections, finite_map, road, road_slope, domain, settings.speed,
                        AdaptiveSystem::LearningSignal::from_phi);
  infinite.set_shuttle(settings.shuttle_from, settings.shuttle_length);
  finite.set_shuttle(settings.shuttle_from, settings.shuttle_length);

  auto kinks = kernel.kink_points();
  for (double kink : target.kink_points()) kinks.push_back(kink);
  std::sort(kinks.begin(), kinks.end());
  const double final_time = settings.final_time_or_laps(domain.length);
  if (!(final_time > 0)) throw std::invalid_argument("the final time must be positive");
  const auto points = adaptive_breakpoints(settings, domain, 0.0, final_time, kinks,
                                           integrator.restarts_at_kinks());
  std::vector<double> times(points.size());
  std::transform(points.begin(), points.end(), times.begin(), [](const auto& p) { return p.t; });
  out.breakpoints = times.size();

  // The infinite estimator's state at every breakpoint, then the finite one against it.
  Eigen::MatrixXd infinite_states(2 * d + F, static_cast<Eigen::Index>(times.size()));
  {
    Eigen::VectorXd z = Eigen::VectorXd::Zero(infinite.dimension());
    integrator.integrate(infinite, z, times, [&](std::size_t k, const double* state) {
      check_cancelled();
      infinite_states.col(static_cast<Eigen::Index>(k)) =
          Eigen::Map<const Eigen::VectorXd>(state, infinite.dimension());
    });
  }
  Eigen::VectorXd gap(V.rows()), gap_on_grid(on_grid.rows());
  double largest_state = 0, largest_coefficients = 0;
  Eigen::VectorXd z = Eigen::VectorXd::Zero(finite.dimension());
  integrator.integrate(finite, z, times, [&](std::size_t k, const double* state) {
    check_cancelled();
    const Eigen::Map<const Eigen::VectorXd> x_j(state, d), xhat_j(state + d, d),
        a(state + 2 * d, dimension);
    const auto reference = infinite_states.col(static_cast<Eigen::Index>(k));
    coordinates.gap(reference.tail(F), a, gap);
    gap_on_grid.noalias() = on_grid * gap;
    const double gap_H = coordinates.norm_H(gap);
    out.estimate_gap_H = std::max(out.estimate_gap_H, gap_H);
    out.estimate_gap_C = std::max(out.estimate_gap_C, gap_on_grid.cwiseAbs().maxCoeff());
    out.state_gap = std::max(out.state_gap, (reference.segment(d, d) - xhat_j).norm());
    out.plant_gap = std::max(out.plant_gap, (reference.head(d) - x_j).norm());
    largest_state = std::max(largest_state, reference.head(d).norm());
    largest_coefficients = std::max(largest_coefficients, reference.tail(F).norm());
  });
  out.gaps_at_integration_floor = out.estimate_gap_H <= 10 * largest_coefficients * out.plant_gap /
                                                            std::max(largest_state, 1e-300);
  {
    const double rtol = std::max(settings.integrator_rtol, 0.0);
    const double atol = std::max(settings.integrator_atol, 0.0);
    const double discrepancy = 10 * out.plant_gap / std::max(largest_state, 1e-300);
    const double relative = rtol + discrepancy;
    const double largest_section = std::sqrt(kernel.diagonal(grid).maxCoeff());
    out.estimate_gap_H_floor = relative * largest_coefficients;
    out.estimate_gap_C_floor = out.estimate_gap_H_floor * largest_section;
    out.state_gap_floor = relative * largest_state + atol;
    out.plant_gap_floor = rtol * largest_state + atol;
  }

  // ||f - Pi_j^* fhat_j(T)|| in L2 on the grid, and the projection's norms there.
  const Eigen::VectorXd estimate = on_grid * (V * z.tail(dimension));
  Eigen::VectorXd residual(estimate.size());
  for (Eigen::Index m = 0; m < residual.size(); ++m)
    residual(m) = target(grid[static_cast<std::size_t>(m)]) - estimate(m);
  out.projected_l2_error = domain.l2_norm(
      std::span<const double>(residual.data(), static_cast<std::size_t>(residual.size())));
  out.projected_l2_error_floor =
      std::max(settings.integrator_rtol, 0.0) *
      domain.l2_norm(std::span<const double>(estimate.data(),
                                             static_cast<std::size_t>(estimate.size())));
  out.projection_norm_H_to_C = projection_residual_norms(kernel, op, grid).maxCoeff();
  out.projection_norm_floor = projection_norm_floor(kernel, op, grid);
  out.projection_norm_at_floor = out.projection_norm_H_to_C <= out.projection_norm_floor;
  out.projection_operator_norm =
      projection_operator_norm(kernel, op, &out.projection_operator_norm_floor);
  return out;
}

void record_estimate_gaps(const EstimateGaps& gaps, AdaptiveMeasurement& out) {
  using M = AdaptiveMetric;
  auto& metrics = out.metrics;
  metrics[M::projection_norm_H_to_C] = gaps.projection_norm_H_to_C;
  metrics[M::projection_operator_norm] = gaps.projection_operator_norm;
  metrics[M::projected_l2_error] = gaps.projected_l2_error;
  metrics[M::estimate_gap_H] = gaps.estimate_gap_H;
  metrics[M::estimate_gap_C] = gaps.estimate_gap_C;
  metrics[M::state_gap] = gaps.state_gap;
  metrics[M::plant_gap] = gaps.plant_gap;
  metrics[M::gap_effectivity_H] = gaps.estimate_gap_H / gaps.projection_norm_H_to_C;
  metrics[M::gap_effectivity_C] = gaps.estimate_gap_C / gaps.projection_norm_H_to_C;
  auto& floors = out.floors;
  floors[M::projection_norm_H_to_C] = gaps.projection_norm_floor;
  floors[M::projection_operator_norm] = gaps.projection_operator_norm_floor;
  floors[M::projected_l2_error] = gaps.projected_l2_error_floor;
  floors[M::estimate_gap_H] = gaps.estimate_gap_H_floor;
  floors[M::estimate_gap_C] = gaps.estimate_gap_C_floor;
  floors[M::state_gap] = gaps.state_gap_floor;
  floors[M::plant_gap] = gaps.plant_gap_floor;
  // A ratio's relative floor is the sum of its terms' (to first order).
  const double norm_share = gaps.projection_norm_floor / gaps.projection_norm_H_to_C;
  floors[M::gap_effectivity_H] =
      metrics[M::gap_effectivity_H] * (gaps.estimate_gap_H_floor / gaps.estimate_gap_H + norm_share);
  floors[M::gap_effectivity_C] =
      metrics[M::gap_effectivity_C] * (gaps.estimate_gap_C_floor / gaps.estimate_gap_C + norm_share);
  if (gaps.projection_norm_at_floor) out.flags.push_back("projection_norm_at_floor");
  if (gaps.gaps_at_integration_floor) out.flags.push_back("estimate_gap_at_integration_floor");
}

}  // namespace rkhs
