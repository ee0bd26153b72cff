#pragma once
// Adaptive-estimation trials (docs/model.md sections 1-5 and 8): a plant x' = A x + B f(s(t)), the
// estimator xhat' = A xhat + B fhat(s(t)) and a learning law for the coefficients alpha of
// fhat = sum_i alpha_i k(c_i, .), integrated in time along a closed track s(t) = (v t) mod L.

#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "rkhs/adaptive/coupled_structure.hpp"
#include "rkhs/adaptive/learning_map.hpp"
#include "rkhs/adaptive/metrics.hpp"
#include "rkhs/adaptive/weight_matrix.hpp"
#include "rkhs/approx/target.hpp"
#include "rkhs/core/domain.hpp"
#include "rkhs/core/registry.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/kernel/point_sections.hpp"

namespace rkhs {

struct ApproximationMeasurement;  // rkhs/approx/approximation.hpp
struct GramSpectrum;              // rkhs/approx/gram_solver.hpp

/// The coupled system in z = [x (d), xhat (d), alpha (n)]:
///   x'     = A x + B f(s)
///   xhat'  = A xhat + B phi(s)^T alpha
///   alpha' = psi(s) b^T (x - xhat),  b = P B,  psi(s) = Gamma^-1 phi(s) (gradient law)
///                                            or Gamma^-1 G^-1 phi(s) (rkhs law)
/// with s = wrap(v t). It is linear in z for given t; the Jacobian and dF/dt are exact:
///   dF/dt = v [B f'(s); B dphi(s)^T alpha; dpsi(s) b^T (x - xhat)],  dpsi = M dphi,
/// with the kernel's derivative of its sections (KernelBasis::evaluate_derivative: a closed
/// form, or its stated difference for a kernel without one) and the road's slope; at a kink the
/// right-hand derivative, the one the step starting there needs. Evaluations allocate nothing.
///
/// Cost: each rhs() evaluates the basis at one point s, once; each jacobian() evaluates it at s
/// once and its derivative once. With LearningSignal::from_phi, psi is M applied to that one
/// phi(s) (n kernel evaluations per rhs for a direct basis, then O(n), O(n r) or O(n^2) for M
/// by its form: rkhs/adaptive/learning_map.hpp); with LearningSignal::by_basis,
/// psi comes from basis.evaluate_mapped (a second evaluation at s, which for a basis through a
/// sparse feature map costs O(features at s x n) against M phi's O(n^2) for a full M).
class AdaptiveSystem {
 public:
  /// How psi(s) = M phi(s) is obtained (see the class comment).
  enum class LearningSignal { from_phi, by_basis };

  /// `basis` evaluates phi(s); `learning_map` is M with psi = M phi (Gamma^-1 I or
  /// Gamma^-1 G^-1, rkhs/adaptive/learning_map.hpp). `road` is f and `road_slope` f'. All
  /// references must outlive the system.
  /// from_phi applies M in its own form: a scalar (O(n)), low rank (O(n r)) or dense (O(n^2));
  /// by_basis hands M to the basis (KernelBasis::set_map).
  AdaptiveSystem(const Eigen::MatrixXd& A, const Eigen::VectorXd& B, const Eigen::MatrixXd& P,
                 KernelBasis& basis, const LearningMap& learning_map,
                 const std::function<double(double)>& road,
                 const std::function<double(double)>& road_slope, const Domain& domain,
                 double speed, LearningSignal signal = LearningSignal::from_phi);
  /// The same with M as an n x n matrix (LearningMap::dense: a multiple of the identity is
  /// applied as a scalar, any other M as a dense product, with the same operations as a direct
  /// basis's evaluate_mapped: bit-identical).
  AdaptiveSystem(const Eigen::MatrixXd& A, const Eigen::VectorXd& B, const Eigen::MatrixXd& P,
                 KernelBasis& basis, const Eigen::MatrixXd& learning_map,
                 const std::function<double(double)>& road,
                 const std::function<double(double)>& road_slope, const Domain& domain,
                 double speed, LearningSignal signal = LearningSignal::from_phi);

  /// A state-dependent system whose f is a function of a read-out of p > 1 coordinates,
  /// y = C x + y0 in R^p (docs/model.md section 18): the system of set_state_readout with
  ///   dx'/dx = A + B grad f(y)^T C + dh/dx,   dxhat'/dx = dh/dx + B (Dphi(y)^T alpha)^T C,
  ///   dalpha'/dx = psi b^T + (b^T (x - xhat)) M Dphi(y) C,
  /// Dphi the n x p Jacobian of the sections (PointSections::gradient) and psi = M phi. `f`
  /// and `f_gradient` take a point of p coordinates (f_gradient writes p values). The plant's
  /// read-out must be p x d with p = sections.dimension() (std::invalid_argument otherwise).
  /// Every reference must outlive the system.
  AdaptiveSystem(const Eigen::MatrixXd& A, const Eigen::VectorXd& B, const Eigen::MatrixXd& P,
                 const PointSections& sections, const LearningMap& learning_map,
                 const class Plant& plant, const std::function<double(const double*)>& f,
                 const std::function<void(const double*, double*)>& f_gradient,
                 const Domain& domain);

  Eigen::Index dimension() const noexcept { return 2 * d_ + n_; }
  Eigen::Index plant_dimension() const noexcept { return d_; }

  /// Makes f a function of the plant's state (Plant::state_dependent, docs/model.md section 18):
  ///   x'     = A x    + h(t, x) + B f(y),      y = c^T x + y0 (one read-out coordinate)
  ///   xhat'  = A xhat + h(t, x) + B phi(y)^T alpha
  ///   alpha' = psi(y) b^T (x - xhat)
  /// with y wrapped onto a periodic domain. The system is then nonlinear in z: jacobian() and
  /// jacobian_matrix(z, ...) depend on z,
  ///   dx'/dx = A + B f'(y) c^T + dh/dx,   dxhat'/dx = dh/dx + B (dphi(y)^T alpha) c^T,
  ///   dalpha'/dx = psi b^T + (b^T (x - xhat)) dpsi(y) c^T,
  /// dF/dt = [dh/dt; dh/dt; 0], and linearize(), jacobian_matrix(t, J) and rhs_columns(),
  /// which assume a Jacobian independent of z, throw std::logic_error. `plant` must outlive the
  /// system; its read-out must be 1 x d (std::invalid_argument otherwise).
  void set_state_readout(const class Plant& plant);
  bool state_dependent() const noexcept { return plant_ != nullptr; }
  /// p, the read-out's coordinates: 1 for a road plant and for set_state_readout.
  int readout_dimension() const noexcept { return sections_ ? sections_->dimension() : 1; }
  /// y = C x + y0 (every coordinate wrapped onto a periodic domain) for the plant state x (d
  /// values): readout_dimension() values. A road system writes nothing.
  void readout_point(const double* x, double* y) const noexcept {
    if (!plant_) return;
    if (!sections_) {
      y[0] = readout(x);
      return;
    }
    for (Eigen::Index a = 0; a < readout_matrix_.rows(); ++a) {
      double value = readout_offsets_(a);
      for (Eigen::Index i = 0; i < d_; ++i) value += readout_matrix_(a, i) * x[i];
      y[a] = domain_.wrap(value, static_cast<int>(a));
    }
  }
  /// y = c^T x + y0 (wrapped onto a periodic domain) for the plant state x (d values); one
  /// read-out coordinate (set_state_readout).
  double readout(const double* x) const noexcept {
    double y = readout_offset_;
    for (Eigen::Index i = 0; i < d_; ++i) y += readout_(i) * x[i];
    return domain_.periodic ? domain_.wrap(y) : y;
  }
  /// Makes the path a shuttle between `from` and `from + length` (AdaptiveSettings::shuttle_from)
  /// instead of laps around the track; length 0 restores the laps.
  void set_shuttle(double from, double length) noexcept {
    shuttle_from_ = from;
    shuttle_length_ = length;
  }
  /// s(t) on the path.
  double arc_length(double t) const noexcept {
    if (shuttle_length_ <= 0) return domain_.wrap(speed_ * t);
    const double u = std::fmod(speed_ * t, 2 * shuttle_length_);
    return shuttle_from_ + (u < shuttle_length_ ? u : 2 * shuttle_length_ - u);
  }
  /// s'(t): v, or -v on a shuttle's way back (the right-hand value at a turning point).
  double path_velocity(double t) const noexcept {
    if (shuttle_length_ <= 0) return speed_;
    return std::fmod(speed_ * t, 2 * shuttle_length_) < shuttle_length_ ? speed_ : -speed_;
  }

  /// dz = F(z, t). Pointers to dimension() doubles.
  void rhs(const double* z, double* dz, double t) const;
  /// J = dF/dz (row-major, dimension()^2 doubles, every entry written) and dfdt = dF/dt.
  void jacobian(const double* z, double* J, double t, double* dfdt) const;
  /// J = dF/dz at t alone (row-major, every entry written): the dense reference of the
  /// structured stage solves. Counted as a Jacobian evaluation. A state-dependent system
  /// throws std::logic_error (its J depends on z: the overload below).
  void jacobian_matrix(double t, double* J) const;
  /// J = dF/dz at (z, t) (row-major, every entry written), for any system. Counted as a
  /// Jacobian evaluation.
  void jacobian_matrix(const double* z, double t, double* J) const;
  /// dfdt = dF/dt at (z, t).
  void time_derivative(const double* z, double t, double* dfdt) const;
  /// J(t) in structured form (rkhs/adaptive/coupled_structure.hpp): phi and psi at s(t), and
  /// the system's A, B and b (which must outlive `out`). One basis evaluation; counted as a
  /// Jacobian evaluation.
  void linearize(double t, CoupledLinearization& out) const;
  /// The columns of the lap map (rkhs/adaptive/lap_map.hpp): dZ = J(t) Z for each of the
  /// `columns` columns of Z (dimension() rows, column-major), plus the forcing [B f(s); 0; 0]
  /// in the last column, so that the last column follows the system from its own state and
  /// the others its sensitivities to the initial state. One basis evaluation; counted as one
  /// right-hand side.
  void rhs_columns(const double* Z, double* dZ, Eigen::Index columns, double t) const;
  const Eigen::MatrixXd& plant_matrix() const noexcept { return A_; }

  std::size_t rhs_evaluations() const noexcept { return rhs_count_; }
  std::size_t jacobian_evaluations() const noexcept { return jacobian_count_; }

 private:
  /// phi_ = phi(s) and psi_ = psi(s): one basis evaluation (from_phi) or two (by_basis).
  void evaluate_basis(double s) const;
  /// y_ = y(x), phi_ = phi(y) and psi_ = M phi(y) for a read-out of p > 1 coordinates; f(y).
  double evaluate_sections(const double* x) const;
  void state_jacobian(const double* z, double t, double* J) const;
  Eigen::MatrixXd A_;
  Eigen::VectorXd B_, b_;
  KernelBasis* basis_ = nullptr;  // null with sections_
  const std::function<double(double)>* road_ = nullptr;
  const std::function<double(double)>* road_slope_ = nullptr;
  Domain domain_;
  double speed_;
  double shuttle_from_ = 0, shuttle_length_ = 0;
  Eigen::Index d_, n_;
  // State-dependent systems: the plant (null for the road case), c and y0 of the read-out, and
  // h, dh/dx (row-major) and dh/dt.
  const class Plant* plant_ = nullptr;
  Eigen::VectorXd readout_;
  double readout_offset_ = 0;
  mutable Eigen::VectorXd known_, known_time_;
  // Read-outs of p > 1 coordinates: the sections in R^p, C (p x d) and y0, f and grad f, and
  // scratch: y, grad f(y), Dphi^T alpha, a 1 x d row, Dphi and M Dphi (n x p, column-major).
  const PointSections* sections_ = nullptr;
  Eigen::MatrixXd readout_matrix_;
  Eigen::VectorXd readout_offsets_;
  const std::function<double(const double*)>* point_road_ = nullptr;
  const std::function<void(const double*, double*)>* point_road_gradient_ = nullptr;
  mutable Eigen::VectorXd y_, road_gradient_, slope_of_estimate_;
  mutable Eigen::RowVectorXd readout_row_;
  mutable Eigen::MatrixXd dphi_points_, dpsi_points_;
  mutable Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> known_jacobian_;
  LearningSignal signal_;
  LearningMap map_;  // from_phi: M
  mutable std::vector<double> phi_, psi_, dphi_, dpsi_;
  mutable Eigen::MatrixXd column_scratch_;  // rhs_columns: phi^T alpha and b^T (x - xhat)
  mutable std::size_t rhs_count_ = 0, jacobian_count_ = 0;
};

/// The learning signal measure_adaptive uses for `kernel`: by_basis for a kernel with a finite
/// feature map (M applied to its sparse features), from_phi otherwise.
AdaptiveSystem::LearningSignal learning_signal_for(const AnyKernel& kernel);

struct IntegrationStats {
  std::size_t steps = 0;
  std::size_t rejected_steps = 0;
  std::size_t segments = 0;
};

/// Integrates an AdaptiveSystem from t = breakpoints[0] through every later breakpoint,
/// landing exactly on each; `observe(k, z)` is called at breakpoint k (including k = 0) with the
/// state (dimension() doubles).
/// Throws std::runtime_error when the step size underflows or the step budget is exhausted,
/// and when the state becomes non-finite.
///
/// The state is the caller's storage, of fixed size (system.dimension()): an integrator reads
/// the initial state from it and writes the final state into it, and works on copies it owns
/// (nothing it allocates is freed by the caller, nor the reverse: plugin/module.hpp).
/// What an integrator does per step, declared by the integrator (typed, like a kernel's
/// KernelProperties): the trial scheduler's cost estimate reads it (run/trial_cost.hpp) and
/// `rkhs-study list integrators` prints it.
struct IntegratorProperties {
  /// Matrices of the coupled system factorised per step: 0 for an explicit method, 1 for a
  /// Rosenbrock method, 2 for Radau IIA (one real, one complex).
  int factorisations_per_step = 1;
  /// Stage systems solved with the Jacobian's structure (block and rank-one: O(d^2 + n) per
  /// stage, rkhs/adaptive/stage_solves.hpp) rather than as the dense (2d + n)^2 matrix.
  bool structured_stage_solves = false;
  bool implicit() const noexcept { return factorisations_per_step > 0; }
};

/// "explicit"; "implicit, 1 factorisation per step, structured stage solves".
std::string describe_integrator(const IntegratorProperties& properties);

class Integrator {
 public:
  virtual ~Integrator() = default;
  virtual IntegrationStats integrate(
      AdaptiveSystem& system, Eigen::Ref<Eigen::VectorXd> state,
      std::span<const double> breakpoints,
      const std::function<void(std::size_t, const double*)>& observe) const = 0;
  /// Whether to stop and restart at the kinks of phi(s(t)) and f(s(t)).
  virtual bool restarts_at_kinks() const noexcept = 0;
  /// What it does per step. The default is the dearer guess for an integrator that does not
  /// say: implicit, one dense factorisation per step.
  virtual IntegratorProperties properties() const noexcept { return {}; }
};

using IntegratorRegistry = Registry<Integrator>;
/// The integrator registry (defined in this layer, registries.cpp), named integrator_kind_name.
inline constexpr std::string_view integrator_kind_name = "integrator";
IntegratorRegistry& integrator_registry();

/// Registers integrator type T (static info(), constructor from ParameterSet). Never throws; a
/// failure is recorded in integrator_registry().errors() (register_plugin).
template <class T>
bool register_integrator() noexcept {
  return register_plugin<T>(integrator_registry());
}

/// How an adaptive trial advances in time (docs/model.md, "the lap map").
///   time_stepping: the integrator steps through every lap;
///   lap_map: one lap is computed once as the affine map z -> Phi z + c (the monodromy matrix
///     of the periodic linear system) and N laps are its N-th power, or its fixed point for
///     laps = "limit"; applies to a periodic domain, a periodic road and a whole number of laps
///     starting at t = 0;
///   automatic: the lap map where it applies, time stepping otherwise.
enum class AdaptiveEngine { automatic, lap_map, time_stepping };

/// "automatic", "lap_map", "time_stepping": the names of [adaptive] engine, of trials.csv's
/// engine column and of the result store's records.
std::string_view adaptive_engine_name(AdaptiveEngine engine) noexcept;

/// The engine `name` stands for; std::nullopt for an unknown name.
std::optional<AdaptiveEngine> adaptive_engine_from_name(std::string_view name) noexcept;

/// Study-wide settings of adaptive trials ([adaptive] in a study file).
struct AdaptiveSettings {
  double speed = 1.0;                 ///< v, m/s
  /// T = laps L / v unless final_time > 0. +infinity stands for laps = "limit": the periodic
  /// steady state (lap map only).
  double laps = 10;
  double final_time = 0;              ///< s
  WeightMatrix q;                     ///< Q of the Lyapunov equation
  bool projected_road = false;        ///< drive the plant with Pi_n f (in H_n) instead of f
  std::vector<double> snapshot_laps;  ///< laps at which fhat is recorded (estimates.csv)
  std::size_t snapshot_points = 256;  ///< points of the snapshot grid
  std::size_t samples_per_lap = 20;   ///< output samples for V and |x - xhat|
  AdaptiveEngine engine = AdaptiveEngine::automatic;
  /// Tolerances of the one lap integrated for the lap map: its errors grow at most N-fold over
  /// N laps. atol below about 1e-10 asks for more than round-off allows in the quarter car's
  /// velocities (computed from forces of 1e5 that cancel): Newton iterations then stall.
  double lap_map_rtol = 1e-10;
  double lap_map_atol = 1e-10;
  /// The trial's integrator's tolerances (its rtol and atol parameters; 0 for an integrator
  /// without them, and then no integration floor is estimated): the scale of the integration
  /// floors (FloorRule::integration). Set per trial by trial_adaptive_settings from the
  /// integrator's parameters (which are part of the trial's identity), never read from a file.
  double integrator_rtol = 0;
  double integrator_atol = 0;
  /// The path s(t): every lap around the track (shuttle_length = 0, s = v t mod L), or a shuttle
  /// back and forth between shuttle_from and shuttle_from + shuttle_length (`[adaptive] path`):
  /// s = from + u for u = v t mod 2l below l, from + 2l - u above, so that a "lap" is one round
  /// trip of length 2l. A shuttle over part of the track leaves the rest unexcited.
  double shuttle_from = 0;
  double shuttle_length = 0;
  /// Theorem 1's metrics (embedding_constant, lipschitz_constant, initial_data_lipschitz,
  /// lipschitz_exponent): set by trial_adaptive_settings when the study asks for one of them,
  /// never read from a file. The measured two cost a second integration from perturbed initial
  /// data (time stepping only).
  bool initial_data_dependence = false;
  bool limit() const noexcept { return std::isinf(laps); }
  bool shuttle() const noexcept { return shuttle_length > 0; }
  /// The distance travelled in one lap: L, or 2l for a shuttle.
  double lap_length(double track_length) const noexcept {
    return shuttle() ? 2 * shuttle_length : track_length;
  }
  double lap_time(double track_length) const noexcept {
    return lap_length(track_length) / speed;
  }
  double final_time_or_laps(double length) const {
    return final_time > 0 ? final_time : laps * lap_time(length);
  }
};

/// The engine measure_adaptive runs a trial with, for a coupled system of `dimension` states:
/// the lap map needs whole laps from t = 0 (no final_time) and whole snapshot laps; `automatic`
/// takes it for laps = "limit" and when the laps outnumber the columns it integrates
/// (dimension + 1), time stepping otherwise. Throws std::invalid_argument when the engine asked
/// for cannot run these settings (the limit without the lap map, the lap map with fractional
/// laps or a final time).
AdaptiveEngine adaptive_engine_for(const AdaptiveSettings& settings, Eigen::Index dimension);

/// Names of the metrics of an adaptive trial, in output order (docs/metrics.md): the names
/// of MetricTable<AdaptiveMetric> (rkhs/adaptive/metrics.hpp).
const std::vector<std::string>& adaptive_metric_names();

struct TimeSample {
  double t;
  double state_error;  ///< |x - xhat|
  double lyapunov;     ///< V(t)
};

struct Snapshot {
  double lap;
  std::vector<double> estimate;  ///< fhat on the snapshot grid
};

struct AdaptiveMeasurement {
  MetricValues<AdaptiveMetric> metrics;  ///< in adaptive_metric_names() order
  /// The floor of each metric (MetricRow::floor; NaN: exact, or not estimated by this trial).
  MetricValues<AdaptiveMetric> floors;
  std::string solve_method;
  AdaptiveEngine engine = AdaptiveEngine::time_stepping;  ///< the one the trial ran with
  std::vector<std::string> flags;
  std::vector<TimeSample> samples;
  std::vector<double> road;  ///< f on the snapshot grid
  std::vector<Snapshot> snapshots;
  /// Wall time of the reference integration (0 without a reference): run_trial leaves it out
  /// of the trial's wall time, which then measures the trial's own integrator.
  double reference_seconds = 0;
};

/// Sets the floors of `out`'s values computed from the integrated state (FloorRule::integration,
/// docs/metrics.md "Floors"): the tolerance the state z(T) is known to, rtol |z| + atol, carried
/// to each value's scale: `estimate` (fhat(T) on the evaluation grid), `alpha` (its
/// coefficients), `alpha_star` (those of Pi_n f), `largest_state_pair` (max over the samples of
/// |x| + |xhat|, d the plant's dimension) and `basis_scale` (the largest sum of |basis values| at
/// a grid point). Time stepping: settings.integrator_rtol and _atol (nothing is set when rtol is
/// 0: an integrator without tolerances). The lap map: the floors of its own metrics from the
/// spectral radius's `radius_uncertainty` (rkhs/adaptive/lap_map.hpp); the caller replaces
/// those of the state its powers give by the spread under a perturbation of the map.
void set_integration_floors(const AdaptiveSettings& settings, AdaptiveEngine engine,
                            const Domain& domain, const Eigen::VectorXd& estimate,
                            const Eigen::VectorXd& alpha, const Eigen::VectorXd& alpha_star,
                            double largest_state_pair, Eigen::Index d, double basis_scale,
                            double radius_uncertainty, AdaptiveMeasurement& out);

/// Sets the floors of `out`'s metrics that come from the trial's static part: those of
/// `approximation` (gram_condition_number, power_function_sup, and interpolant_l2_error and
/// interpolant_sup_error from its l2_error and sup_error), and those of P_L2 f, from a solve with
/// the Gram matrix of `spectrum` (n centres): solve_round_off times its size in L2
/// (`l2_projection_l2`) and on the grid (`l2_projection_sup`).
void set_static_floors(const ApproximationMeasurement& approximation, const GramSpectrum& spectrum,
                       Eigen::Index n, double l2_projection_l2, double l2_projection_sup,
                       AdaptiveMeasurement& out);

/// Runs one adaptive trial. Throws on invalid input or failed integration. A plant with
/// Plant::state_dependent() is measured by measure_state_dependent
/// (rkhs/adaptive/state_dependent.hpp; the lap map cache is not used).
///
/// With a `reference` integrator ([adaptive] reference), the trial must step through time
/// (adaptive_engine_for must give time_stepping; std::invalid_argument otherwise): after the
/// trial's own integration the same system is integrated again from z = 0 over the same
/// breakpoints with `reference`, and integration_error = ||fhat(T) - fhat_ref(T)||_L2 /
/// ||fhat_ref(T)||_L2 on the evaluation grid. steps, rhs_evaluations and the other cost metrics
/// count the trial's own integrator only. Without a reference integration_error is NaN.
///
/// With `lap_maps`, a lap map is looked up under `lap_map_key` (which must identify everything
/// but the lap count) and computed only if no trial of the run has (rkhs/adaptive/lap_map.hpp).
AdaptiveMeasurement measure_adaptive(const AnyKernel& kernel, const TargetFunction& target,
                                     std::span<const double> centres, const class Plant& plant,
                                     const class LearningLaw& law, const Integrator& integrator,
                                     const AdaptiveSettings& settings,
                                     std::size_t evaluation_points,
                                     const struct SolverOptions& solver,
                                     const Integrator* reference = nullptr,
                                     class LapMapCache* lap_maps = nullptr,
                                     const std::string& lap_map_key = {});

}  // namespace rkhs

#define RKHS_REGISTER_INTEGRATOR(Type) \
  RKHS_REGISTRAR(rkhs_integrator_registered_, ::rkhs::register_integrator<Type>())
