// Built-in integrators over Boost.Odeint: rosenbrock4 (L-stable, with the exact Jacobian of the
// coupled system), dopri5 and rk_fehlberg78 (adaptive explicit), rk4 (fixed step).
#include <fmt/format.h>

#include <boost/numeric/odeint.hpp>
#include <cmath>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/adaptive/stepping.hpp"

namespace rkhs {
namespace {

namespace odeint = boost::numeric::odeint;
using State = boost::numeric::ublas::vector<double>;
using Matrix = boost::numeric::ublas::matrix<double>;

struct Rhs {
  AdaptiveSystem* system;
  void operator()(const State& z, State& dz, double t) const {
    system->rhs(&z.data()[0], &dz.data()[0], t);
  }
};

struct Jacobian {
  AdaptiveSystem* system;
  void operator()(const State& z, Matrix& J, const double& t, State& dfdt) const {
    // ublas matrices are row-major by default: J's storage is the row-major array.
    system->jacobian(&z.data()[0], &J.data()[0], t, &dfdt.data()[0]);
  }
};

std::vector<ParameterSpec> adaptive_parameters() {
  return {positive_parameter("rtol", 1e-6, "relative tolerance"),
          positive_parameter("atol", 1e-8, "absolute tolerance"),
          integer_parameter("max_steps", 20'000'000, "step budget of a trial", 1, 1LL << 40),
          real_parameter("initial_step", 0.0, "first step, s (0: 1e-6 of the first segment)", 0.0),
          boolean_parameter("restart_at_kinks", true,
                            "stop and restart where phi(s(t)) or f(s(t)) has kinks")};
}

// The settings every adaptive-step integrator reads from its parameters.
class AdaptiveStepIntegrator : public Integrator {
 public:
  explicit AdaptiveStepIntegrator(const ParameterSet& p)
      : rtol_(p.real("rtol")),
        atol_(p.real("atol")),
        max_steps_(p.integer("max_steps")),
        initial_step_(p.real("initial_step")),
        restart_(p.boolean("restart_at_kinks")) {}
  bool restarts_at_kinks() const noexcept override { return restart_; }

 protected:
  double rtol_, atol_;
  std::int64_t max_steps_;
  double initial_step_;
  bool restart_;
};

// An odeint controlled stepper (or one with its try_step signature, Rodas4Stepper) as a
// SteppingPolicy: it owns the state as the ublas vector the stepper works on.
template <class Controlled, class System>
class ControlledPolicy {
 public:
  ControlledPolicy(Controlled& stepper, System system, Eigen::Index dimension)
      : stepper_(stepper), system_(system), x_(static_cast<std::size_t>(dimension)) {}
  double* state() { return &x_.data()[0]; }
  StepOutcome try_step(double& t, double& dt) {
    return stepper_.try_step(system_, x_, t, dt) == odeint::success ? StepOutcome::accepted
                                                                    : StepOutcome::rejected;
  }
  void reset()
    requires requires(Controlled& c) { c.reset(); }
  {
    stepper_.reset();
  }

 private:
  Controlled& stepper_;
  System system_;
  State x_;
};

template <class Controlled, class System>
IntegrationStats drive_controlled(Controlled& stepper, System system, AdaptiveSystem& adaptive,
                                  Eigen::VectorXd& z, std::span<const double> breakpoints,
                                  const std::function<void(std::size_t, const double*)>& observe,
                                  std::int64_t max_steps, double initial_step,
                                  bool reset_segments) {
  ControlledPolicy<Controlled, System> policy(stepper, system, z.size());
  return drive_steps(policy, adaptive, z, breakpoints, observe,
                     {max_steps, initial_step, reset_segments, {}});
}

/// The coefficients of odeint's rosenbrock4 (Hairer and Wanner's RODAS4) with the sign of
/// d4 = gamma_4 corrected: Boost 1.81 has d4 = +0.0362, RODAS4 has -0.0362 (Hairer's rodas.f,
/// Sandu's KPP). The term only matters when F depends on t, as it does here through s(t), and
/// the wrong sign cuts the method to first order on forced problems (an exactly representable
/// slow solution of y' = -400 y + g(t) gets a local error of 1.5e-7 at h = 1e-3 instead of
/// round-off; tests/adaptive keeps this measured).
struct CorrectedRosenbrockCoefficients : odeint::default_rosenbrock_coefficients<double> {
  const double d4 = -0.3620000000000023e-01;
};

class Rosenbrock4 final : public AdaptiveStepIntegrator {
 public:
  static PluginInfo info() {
    return {"rosenbrock4",
            "4th-order L-stable Rosenbrock method with the exact Jacobian (for stiff systems)",
            adaptive_parameters(),
            {{"implicit", "yes, one LU factorisation per step"}}};
  }
  explicit Rosenbrock4(const ParameterSet& p) : AdaptiveStepIntegrator(p) {}
  IntegrationStats integrate(
      AdaptiveSystem& system, Eigen::VectorXd& z, std::span<const double> breakpoints,
      const std::function<void(std::size_t, const double*)>& observe) const override {
    using Stepper = odeint::rosenbrock4<double, CorrectedRosenbrockCoefficients>;
    odeint::rosenbrock4_controller<Stepper> stepper(atol_, rtol_);
    return drive_controlled(stepper, std::make_pair(Rhs{&system}, Jacobian{&system}), system, z,
                          breakpoints, observe, max_steps_, initial_step_, false);
  }
};

/// RODAS4 (Hairer and Wanner, Solving ODEs II, Sec. IV.7): a 6-stage, order 4(3), L-stable
/// and stiffly accurate Rosenbrock method, the method of odeint's rosenbrock4 (with the
/// corrected d4), here with dense Eigen storage and a blocked LU factorisation. Stage i solves (I /
/// (h gamma) - J) k_i = F(t + alpha_i h, z + sum_j a_ij k_j)
///   + sum_j c_ij k_j / h + h gamma_i dF/dt; the step is z + sum_j m_j k_j, its error k_6.
class Rodas4Stepper {
 public:
  Rodas4Stepper(AdaptiveSystem& system, double atol, double rtol)
      : system_(system),
        atol_(atol),
        rtol_(rtol),
        m_(system.dimension()),
        jacobian_(m_, m_),
        matrix_(m_, m_),
        dfdt_(m_),
        stage_(m_),
        value_(m_),
        k_(m_, 6),
        next_(m_) {}

  template <class Ignored>
  odeint::controlled_step_result try_step(Ignored, State& x, double& t, double& dt) {
    constexpr double gamma = 0.25;
    static constexpr double alpha[6] = {0.0, 0.386, 0.210, 0.630, 1.0, 1.0};
    static constexpr double gammas[6] = {0.25, -0.1043, 0.1035, -0.3620000000000023e-01, 0.0, 0.0};
    static constexpr double a[6][5] = {
        {},
        {0.1544000000000000e+01},
        {0.9466785280815826e+00, 0.2557011698983284e+00},
        {0.3314825187068521e+01, 0.2896124015972201e+01, 0.9986419139977817e+00},
        {0.1221224509226641e+01, 0.6019134481288629e+01, 0.1253708332932087e+02,
         -0.6878860361058950e+00},
        {0.1221224509226641e+01, 0.6019134481288629e+01, 0.1253708332932087e+02,
         -0.6878860361058950e+00, 1.0}};
    static constexpr double c[6][5] = {
        {},
        {-0.5668800000000000e+01},
        {-0.2430093356833875e+01, -0.2063599157091915e+00},
        {-0.1073529058151375e+00, -0.9594562251023355e+01, -0.2047028614809616e+02},
        {0.7496443313967647e+01, -0.1024680431464352e+02, -0.3399990352819905e+02,
         0.1170890893206160e+02},
        {0.8083246795921522e+01, -0.7981132988064893e+01, -0.3152159432874371e+02,
         0.1631930543123136e+02, -0.6058818238834054e+01}};
    static constexpr double weights[6] = {0.1221224509226641e+01,
                                          0.6019134481288629e+01,
                                          0.1253708332932087e+02,
                                          -0.6878860361058950e+00,
                                          1.0,
                                          1.0};
    Eigen::Map<Eigen::VectorXd> z(&x.data()[0], m_);
    const double h = dt;
    system_.jacobian(z.data(), jacobian_.data(), t, dfdt_.data());
    matrix_ = -jacobian_;
    matrix_.diagonal().array() += 1.0 / (h * gamma);
    lu_.compute(matrix_);
    for (int i = 0; i < 6; ++i) {
      stage_ = z;
      for (int j = 0; j < i; ++j) stage_.noalias() += a[i][j] * k_.col(j);
      system_.rhs(stage_.data(), value_.data(), t + alpha[i] * h);
      for (int j = 0; j < i; ++j) value_.noalias() += (c[i][j] / h) * k_.col(j);
      value_.noalias() += (h * gammas[i]) * dfdt_;
      k_.col(i) = lu_.solve(value_);
    }
    next_ = z;
    for (int j = 0; j < 6; ++j) next_.noalias() += weights[j] * k_.col(j);
    // RMS norm of the error estimate k_6, scaled per component.
    double sum = 0;
    for (Eigen::Index i = 0; i < m_; ++i) {
      const double scale = atol_ + rtol_ * std::max(std::abs(z(i)), std::abs(next_(i)));
      sum += std::pow(k_(i, 5) / scale, 2);
    }
    const double error = std::sqrt(sum / static_cast<double>(m_));
    const double factor =
        std::min(6.0, std::max(0.2, 0.9 / std::pow(std::max(error, 1e-300), 0.25)));
    if (!(error <= 1.0)) {  // also rejects NaN
      dt = h * (std::isfinite(error) ? std::min(factor, 1.0) : 0.1);
      rejected_last_ = true;
      return odeint::fail;
    }
    z = next_;
    t += h;
    dt = rejected_last_ ? std::min(h * factor, h) : h * factor;
    rejected_last_ = false;
    return odeint::success;
  }

 private:
  AdaptiveSystem& system_;
  double atol_, rtol_;
  Eigen::Index m_;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> jacobian_;
  Eigen::MatrixXd matrix_;
  Eigen::PartialPivLU<Eigen::MatrixXd> lu_;
  Eigen::VectorXd dfdt_, stage_, value_;
  Eigen::MatrixXd k_;
  Eigen::VectorXd next_;
  bool rejected_last_ = false;
};

class Rodas4 final : public AdaptiveStepIntegrator {
 public:
  static PluginInfo info() {
    return {"rodas4",
            "RODAS4, the method of rosenbrock4, with Eigen's blocked LU (about 3x faster at "
            "n = 100)",
            adaptive_parameters(),
            {{"implicit", "yes, one LU factorisation per step"}}};
  }
  explicit Rodas4(const ParameterSet& p) : AdaptiveStepIntegrator(p) {}
  IntegrationStats integrate(
      AdaptiveSystem& system, Eigen::VectorXd& z, std::span<const double> breakpoints,
      const std::function<void(std::size_t, const double*)>& observe) const override {
    Rodas4Stepper stepper(system, atol_, rtol_);
    return drive_controlled(stepper, 0, system, z, breakpoints, observe, max_steps_, initial_step_,
                          false);
  }
};

/// An adaptive explicit Runge-Kutta pair; `Describe` supplies the plugin's info().
template <class Stepper, class Describe>
class ExplicitAdaptive final : public AdaptiveStepIntegrator {
 public:
  static PluginInfo info() { return Describe::info(); }
  explicit ExplicitAdaptive(const ParameterSet& p) : AdaptiveStepIntegrator(p) {}
  IntegrationStats integrate(
      AdaptiveSystem& system, Eigen::VectorXd& z, std::span<const double> breakpoints,
      const std::function<void(std::size_t, const double*)>& observe) const override {
    auto stepper = odeint::make_controlled(atol_, rtol_, Stepper());
    // Reset per segment: a first-same-as-last derivative must not cross a kink.
    return drive_controlled(stepper, Rhs{&system}, system, z, breakpoints, observe, max_steps_,
                          initial_step_, true);
  }
};

struct Dopri5 {
  static PluginInfo info() {
    return {"dopri5",
            "Dormand-Prince 5(4), adaptive explicit (non-stiff checks, short horizons)",
            adaptive_parameters(),
            {{"implicit", "no"}}};
  }
};
struct Fehlberg78 {
  static PluginInfo info() {
    return {"rk_fehlberg78",
            "Runge-Kutta-Fehlberg 7(8), adaptive explicit, high order",
            adaptive_parameters(),
            {{"implicit", "no"}}};
  }
};
using Dopri5Integrator = ExplicitAdaptive<odeint::runge_kutta_dopri5<State>, Dopri5>;
using Fehlberg78Integrator = ExplicitAdaptive<odeint::runge_kutta_fehlberg78<State>, Fehlberg78>;

// odeint's classical Runge-Kutta as a SteppingPolicy: every step is accepted at the size it
// is given (the driver shortens it to land on breakpoints).
class FixedStep {
 public:
  FixedStep(AdaptiveSystem& system, Eigen::Index dimension)
      : rhs_{&system}, x_(static_cast<std::size_t>(dimension)) {}
  double* state() { return &x_.data()[0]; }
  StepOutcome try_step(double& t, double& dt) {
    stepper_.do_step(rhs_, x_, t, dt);
    t += dt;
    return StepOutcome::accepted;
  }

 private:
  odeint::runge_kutta4<State> stepper_;
  Rhs rhs_;
  State x_;
};

/// Classical Runge-Kutta with a fixed step (shortened to land on breakpoints).
class Rk4 final : public Integrator {
 public:
  static PluginInfo info() {
    return {"rk4",
            "classical 4th-order Runge-Kutta with a fixed step",
            {positive_parameter("step", 1e-3, "step size, s"),
             integer_parameter("max_steps", 20'000'000, "step budget of a trial", 1, 1LL << 40),
             boolean_parameter("restart_at_kinks", true,
                               "stop and restart where phi(s(t)) or f(s(t)) has kinks")},
            {{"implicit", "no"}}};
  }
  explicit Rk4(const ParameterSet& p)
      : step_(p.real("step")),
        max_steps_(p.integer("max_steps")),
        restart_(p.boolean("restart_at_kinks")) {}
  bool restarts_at_kinks() const noexcept override { return restart_; }
  IntegrationStats integrate(
      AdaptiveSystem& system, Eigen::VectorXd& z, std::span<const double> breakpoints,
      const std::function<void(std::size_t, const double*)>& observe) const override {
    FixedStep policy(system, z.size());
    return drive_steps(
        policy, system, z, breakpoints, observe,
        {max_steps_, step_, false,
         fmt::format(" (step {} s too large for this stiff system?)", format_real(step_))});
  }

 private:
  double step_;
  std::int64_t max_steps_;
  bool restart_;
};

}  // namespace
}  // namespace rkhs

RKHS_REGISTER_INTEGRATOR(rkhs::Rodas4)
RKHS_REGISTER_INTEGRATOR(rkhs::Rosenbrock4)
RKHS_REGISTER_INTEGRATOR(rkhs::Dopri5Integrator)
RKHS_REGISTER_INTEGRATOR(rkhs::Fehlberg78Integrator)
RKHS_REGISTER_INTEGRATOR(rkhs::Rk4)
