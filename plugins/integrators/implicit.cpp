// Built-in implicit integrators whose stage equations use the structure of the coupled
// system's Jacobian (rkhs/adaptive/stage_solves.hpp): radau5 (Radau IIA, order 5) and rodas4
// (RODAS4, order 4). Both take linear_solver = "structured" (default: O(d^2 + n) per stage
// solve) or "dense" (the (2d + n)^2 reference).
#include <fmt/format.h>

#include <cmath>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/adaptive/radau.hpp"
#include "rkhs/adaptive/stage_solves.hpp"
#include "rkhs/adaptive/stepping.hpp"
#include "rkhs/integrators/adaptive_step.hpp"

namespace rkhs {
namespace {

using integrators::AdaptiveStepIntegrator;

std::vector<ParameterSpec> implicit_parameters() {
  auto parameters = integrators::adaptive_step_parameters();
  parameters.push_back(choice_parameter(
      "linear_solver", "structured",
      "stage solves: structured (one d x d factorisation and a scalar Schur complement, "
      "O(d^2 + n)) or dense (the (2d + n)^2 matrix, the reference)",
      {"structured", "dense"}));
  return parameters;
}

class Radau5 final : public AdaptiveStepIntegrator {
 public:
  static PluginInfo info() {
    return {"radau5",
            "Radau IIA of order 5 (3 stages, L-stable, stiffly accurate) with RADAU5's error "
            "estimate and step control; structured stage solves",
            implicit_parameters()};
  }
  explicit Radau5(const ParameterSet& p)
      : AdaptiveStepIntegrator(p), solver_(linear_solver_from_name(p.text("linear_solver"))) {}
  IntegratorProperties properties() const noexcept override {
    return {2, solver_ == LinearSolver::structured};  // one real, one complex
  }
  IntegrationStats integrate(
      AdaptiveSystem& system, Eigen::Ref<Eigen::VectorXd> state,
      std::span<const double> breakpoints,
      const std::function<void(std::size_t, const double*)>& observe) const override {
    Eigen::VectorXd z = state;  // the integrator's own copy (Integrator: the state's owner)
    TrajectoryStages problem(system, solver_);
    RadauIIA5<TrajectoryStages> stepper(problem, atol_, rtol_);
    const IntegrationStats stats =
        drive_steps(stepper, z, breakpoints, observe, {max_steps_, initial_step_, restart_, {}});
    state = z;
    return stats;
  }

 private:
  LinearSolver solver_;
};

/// RODAS4 (Hairer and Wanner, Solving ODEs II, Sec. IV.7): a 6-stage, order 4(3), L-stable
/// and stiffly accurate Rosenbrock method, the method of odeint's rosenbrock4 (with the
/// corrected d4, see odeint_and_rk4.cpp), with structured or dense stage solves. Stage i
/// solves (I / (h gamma) - J) k_i = F(t + alpha_i h, z + sum_j a_ij k_j)
///   + sum_j c_ij k_j / h + h gamma_i dF/dt; the step is z + sum_j m_j k_j, its error k_6.
class Rodas4Stepper {
 public:
  Rodas4Stepper(AdaptiveSystem& system, LinearSolver solver, double atol, double rtol)
      : system_(system),
        solves_(system, solver),
        atol_(atol),
        rtol_(rtol),
        m_(system.dimension()),
        z_(m_),
        dfdt_(m_),
        stage_(m_),
        value_(m_),
        k_(m_, 6),
        next_(m_) {}

  double* state() { return z_.data(); }

  StepOutcome try_step(double& t, double& dt) {
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
    const double h = dt;
    system_.time_derivative(z_.data(), t, dfdt_.data());
    solves_.factor(t, z_.data(), 1.0 / (h * gamma));
    for (int i = 0; i < 6; ++i) {
      stage_ = z_;
      for (int j = 0; j < i; ++j) stage_.noalias() += a[i][j] * k_.col(j);
      system_.rhs(stage_.data(), value_.data(), t + alpha[i] * h);
      for (int j = 0; j < i; ++j) value_.noalias() += (c[i][j] / h) * k_.col(j);
      value_.noalias() += (h * gammas[i]) * dfdt_;
      solves_.solve_real(value_);
      k_.col(i) = value_;
    }
    next_ = z_;
    for (int j = 0; j < 6; ++j) next_.noalias() += weights[j] * k_.col(j);
    // RMS norm of the error estimate k_6, scaled per component.
    double sum = 0;
    for (Eigen::Index i = 0; i < m_; ++i) {
      const double scale = atol_ + rtol_ * std::max(std::abs(z_(i)), std::abs(next_(i)));
      sum += std::pow(k_(i, 5) / scale, 2);
    }
    const double error = std::sqrt(sum / static_cast<double>(m_));
    const double factor =
        std::min(6.0, std::max(0.2, 0.9 / std::pow(std::max(error, 1e-300), 0.25)));
    if (!(error <= 1.0)) {  // also rejects NaN
      dt = h * (std::isfinite(error) ? std::min(factor, 1.0) : 0.1);
      rejected_last_ = true;
      return StepOutcome::rejected;
    }
    z_ = next_;
    t += h;
    dt = rejected_last_ ? std::min(h * factor, h) : h * factor;
    rejected_last_ = false;
    return StepOutcome::accepted;
  }

 private:
  AdaptiveSystem& system_;
  StageSolves solves_;
  double atol_, rtol_;
  Eigen::Index m_;
  Eigen::VectorXd z_, dfdt_, stage_, value_;
  Eigen::MatrixXd k_;
  Eigen::VectorXd next_;
  bool rejected_last_ = false;
};

class Rodas4 final : public AdaptiveStepIntegrator {
 public:
  static PluginInfo info() {
    return {"rodas4",
            "RODAS4 (order 4, L-stable, stiffly accurate Rosenbrock), the method of "
            "rosenbrock4, with structured stage solves",
            implicit_parameters()};
  }
  explicit Rodas4(const ParameterSet& p)
      : AdaptiveStepIntegrator(p), solver_(linear_solver_from_name(p.text("linear_solver"))) {}
  IntegratorProperties properties() const noexcept override {
    return {1, solver_ == LinearSolver::structured};
  }
  IntegrationStats integrate(
      AdaptiveSystem& system, Eigen::Ref<Eigen::VectorXd> state,
      std::span<const double> breakpoints,
      const std::function<void(std::size_t, const double*)>& observe) const override {
    Eigen::VectorXd z = state;  // the integrator's own copy (Integrator: the state's owner)
    Rodas4Stepper stepper(system, solver_, atol_, rtol_);
    const IntegrationStats stats =
        drive_steps(stepper, z, breakpoints, observe, {max_steps_, initial_step_, false, {}});
    state = z;
    return stats;
  }

 private:
  LinearSolver solver_;
};

}  // namespace
}  // namespace rkhs

RKHS_REGISTER_INTEGRATOR(rkhs::Radau5)
RKHS_REGISTER_INTEGRATOR(rkhs::Rodas4)
