// Built-in integrators over Boost.Odeint: rosenbrock4 (L-stable, with the exact Jacobian of the
// coupled system, dense ublas LU), dopri5 and rk_fehlberg78 (adaptive explicit), rk4 (fixed
// step). The integrators with structured stage solves are in implicit.cpp.
#include <fmt/format.h>

#include <boost/numeric/odeint.hpp>
#include <cmath>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/adaptive/stepping.hpp"
#include "rkhs/integrators/adaptive_step.hpp"

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

using integrators::AdaptiveStepIntegrator;
using integrators::adaptive_step_parameters;

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
IntegrationStats drive_controlled(Controlled& stepper, System system, Eigen::VectorXd& z, std::span<const double> breakpoints,
                                  const std::function<void(std::size_t, const double*)>& observe,
                                  std::int64_t max_steps, double initial_step,
                                  bool reset_segments) {
  ControlledPolicy<Controlled, System> policy(stepper, system, z.size());
  return drive_steps(policy, z, breakpoints, observe,
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
            adaptive_step_parameters()};
  }
  explicit Rosenbrock4(const ParameterSet& p) : AdaptiveStepIntegrator(p) {}
  IntegratorProperties properties() const noexcept override {
    return {1, false};  // one dense LU factorisation per step
  }
  IntegrationStats integrate(
      AdaptiveSystem& system, Eigen::Ref<Eigen::VectorXd> state,
      std::span<const double> breakpoints,
      const std::function<void(std::size_t, const double*)>& observe) const override {
    Eigen::VectorXd z = state;  // the integrator's own copy (Integrator: the state's owner)
    using Stepper = odeint::rosenbrock4<double, CorrectedRosenbrockCoefficients>;
    odeint::rosenbrock4_controller<Stepper> stepper(atol_, rtol_);
    const IntegrationStats stats =
        drive_controlled(stepper, std::make_pair(Rhs{&system}, Jacobian{&system}), z, breakpoints,
                         observe, max_steps_, initial_step_, false);
    state = z;
    return stats;
  }
};

/// An adaptive explicit Runge-Kutta pair; `Describe` supplies the plugin's info().
template <class Stepper, class Describe>
class ExplicitAdaptive final : public AdaptiveStepIntegrator {
 public:
  static PluginInfo info() { return Describe::info(); }
  explicit ExplicitAdaptive(const ParameterSet& p) : AdaptiveStepIntegrator(p) {}
  IntegratorProperties properties() const noexcept override { return {0, false}; }
  IntegrationStats integrate(
      AdaptiveSystem& system, Eigen::Ref<Eigen::VectorXd> state,
      std::span<const double> breakpoints,
      const std::function<void(std::size_t, const double*)>& observe) const override {
    Eigen::VectorXd z = state;  // the integrator's own copy (Integrator: the state's owner)
    auto stepper = odeint::make_controlled(atol_, rtol_, Stepper());
    // Reset per segment: a first-same-as-last derivative must not cross a kink.
    const IntegrationStats stats = drive_controlled(stepper, Rhs{&system}, z, breakpoints, observe,
                                                    max_steps_, initial_step_, true);
    state = z;
    return stats;
  }
};

struct Dopri5 {
  static PluginInfo info() {
    return {"dopri5", "Dormand-Prince 5(4), adaptive explicit (non-stiff checks, short horizons)",
            adaptive_step_parameters()};
  }
};
struct Fehlberg78 {
  static PluginInfo info() {
    return {"rk_fehlberg78", "Runge-Kutta-Fehlberg 7(8), adaptive explicit, high order",
            adaptive_step_parameters()};
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
                               "stop and restart where phi(s(t)) or f(s(t)) has kinks")}};
  }
  explicit Rk4(const ParameterSet& p)
      : step_(p.real("step")),
        max_steps_(p.integer("max_steps")),
        restart_(p.boolean("restart_at_kinks")) {}
  bool restarts_at_kinks() const noexcept override { return restart_; }
  IntegratorProperties properties() const noexcept override { return {0, false}; }
  IntegrationStats integrate(
      AdaptiveSystem& system, Eigen::Ref<Eigen::VectorXd> state,
      std::span<const double> breakpoints,
      const std::function<void(std::size_t, const double*)>& observe) const override {
    Eigen::VectorXd z = state;  // the integrator's own copy (Integrator: the state's owner)
    FixedStep policy(system, z.size());
    const IntegrationStats stats = drive_steps(
        policy, z, breakpoints, observe,
        {max_steps_, step_, false,
         fmt::format(" (step {} s too large for this stiff system?)", format_real(step_))});
    state = z;
    return stats;
  }

 private:
  double step_;
  std::int64_t max_steps_;
  bool restart_;
};

}  // namespace
}  // namespace rkhs

RKHS_REGISTER_INTEGRATOR(rkhs::Rosenbrock4)
RKHS_REGISTER_INTEGRATOR(rkhs::Dopri5Integrator)
RKHS_REGISTER_INTEGRATOR(rkhs::Fehlberg78Integrator)
RKHS_REGISTER_INTEGRATOR(rkhs::Rk4)
