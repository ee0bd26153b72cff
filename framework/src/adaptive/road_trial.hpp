#pragma once
// One trial of a road plant (measure_adaptive, rkhs/adaptive/adaptive.hpp), step by step: the
// set-up (the constructor), the integration by time stepping or by the lap map
// (road_lap_map.cpp), and the metrics at the final time.

#include <Eigen/Sparse>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "adaptive_metrics.hpp"
#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/adaptive/breakpoints.hpp"
#include "rkhs/adaptive/lap_map.hpp"
#include "rkhs/adaptive/learning_map.hpp"
#include "rkhs/adaptive/plant.hpp"

namespace rkhs {

struct RoadTrial {
  /// Everything before the integration; throws std::invalid_argument for a kernel the law
  /// cannot use, a Q of the wrong size, or a reference integration the engine cannot run.
  RoadTrial(const AnyKernel& kernel, const TargetFunction& target, std::span<const double> centres,
            const Plant& plant, const LearningLaw& law, const Integrator& integrator,
            const AdaptiveSettings& settings, std::size_t evaluation_points,
            const SolverOptions& solver_options, const Integrator* reference);
  RoadTrial(const RoadTrial&) = delete;
  RoadTrial& operator=(const RoadTrial&) = delete;

  /// Integrates from z = 0 to the final time with the study's integrator.
  void step_through_time();
  /// One lap as an affine map, then N laps (or the limit) through its powers
  /// (road_lap_map.cpp); the map is looked up in `lap_maps` (when given) under `key`.
  void run_lap_map(LapMapCache* lap_maps, const std::string& key);
  /// The metrics and floors at the final time, and integration_error with a `reference`.
  void measure_final(const Integrator* reference);
  /// Theorem 1's metrics (initial_data.cpp), after measure_final: the embedding and Lipschitz
  /// constants, and, after time stepping, a second integration from perturbed initial data
  /// against the states sampled by the first.
  void measure_initial_data_dependence();

  // The trial's inputs.
  const AnyKernel& kernel;
  const TargetFunction& target;
  std::span<const double> centres;
  const Plant& plant;
  const Integrator& integrator;
  const AdaptiveSettings& settings;
  const SolverOptions& solver_options;
  const Domain& domain;
  /// The law's coordinates: alpha over the n sections at the centres, or beta over the
  /// kernel's F features (rkhs_embedding: H itself; the centres then define only the static
  /// part, Pi_n f and the road = "projection").
  const bool in_features;
  AdaptiveMeasurement out;
  const StaticPart fixed;

  // The adaptive system.
  double gamma = 0;
  std::unique_ptr<KernelBasis> basis;  ///< the estimator's: sections (n) or features (F)
  Eigen::Index coefficients = 0;       ///< n, or F
  bool gram_inverse = false;
  std::optional<LearningMap> learning_map;
  Eigen::Index d = 0;
  Eigen::MatrixXd P;
  std::unique_ptr<KernelBasis> road_basis;
  std::vector<double> road_phi;
  std::function<double(double)> road, road_slope;  ///< f, or Pi_n f
  std::optional<AdaptiveSystem> system;
  std::vector<double> kinks;  ///< of phi(s), and of f (a sampled road)
  Eigen::Index m = 0;
  double lap_time = 0;
  AdaptiveEngine engine = AdaptiveEngine::time_stepping;

  // The grids and the coefficients of the road = "projection" in the law's coordinates.
  std::vector<double> grid, snapshot_grid;
  Eigen::SparseMatrix<double, Eigen::RowMajor> grid_features, snapshot_features;
  Eigen::MatrixXd snapshot_cross;
  Eigen::VectorXd coefficients_star;

  // What the integration leaves.
  double largest_state_pair = 0;  ///< max over the samples of |x| + |xhat| (the floors' scale)
  /// z at each sample (aligned with out.samples), kept when settings.initial_data_dependence.
  std::vector<Eigen::VectorXd> sampled_states;
  IntegrationStats stats;
  Eigen::VectorXd z;               ///< the state at the final time
  Eigen::VectorXd lap_map_spread;  ///< lap map: z from the perturbed map minus z (the floors)
  std::shared_ptr<const LapMap> lap_map;
  double radius_uncertainty = std::numeric_limits<double>::quiet_NaN();  ///< lap map only
  std::size_t reused_rhs_evaluations = 0, reused_jacobian_evaluations = 0;

  /// The estimate on the evaluation grid from coefficients `c`.
  Eigen::VectorXd on_grid(const Eigen::VectorXd& c) const;
  void sample(double t, const double* state);
  void snapshot(std::size_t index, const double* state);
  /// Integrates from `state` at t = start through `points` (times from start on) with the
  /// study's integrator, sampling and taking snapshots where the points say.
  void integrate(Eigen::VectorXd& state, const std::vector<Breakpoint>& points);

 private:
  void set_up_grids(std::size_t evaluation_points);
  /// P_L2 f and pe_level, then the shared metrics (set_shared_metrics); returns the residual.
  Eigen::VectorXd measure_against_limit(const Eigen::VectorXd& f, const Eigen::VectorXd& alpha,
                                        const Eigen::VectorXd& estimate);
  void set_decay_rates();
  void set_lap_map_floors();
  void set_integration_error(const Integrator& reference, const Eigen::VectorXd& estimate);
};

}  // namespace rkhs
