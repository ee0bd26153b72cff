// Built-in state-dependent plants (docs/model.md section 18): forced oscillators whose unknown
// function f is a function of their state, x' = A x + h(t, x) + B f(c^T x + y0).
//
//   duffing   q'' + delta q' + alpha q = f(q + y0) + gamma cos(omega t): f an unknown stiffness
//             law (the Duffing oscillator's -beta q^3, written as a target in y = q + y0);
//             with readout = "state", f(q + y0, q' + y0') of the whole state, an unknown law of
//             stiffness and damping on a domain of d = 2.
//   pendulum  theta'' + (g / l) sin(theta) + c theta' = f(theta' + y0) + gamma cos(omega t): f an
//             unknown friction law of the angular velocity; the gravity term is known and
//             nonlinear, h = [0, -(g/l) (sin(theta) - theta) + gamma cos(omega t)].
//
// Both have the state x = [q, q'] (or [theta, theta']), B = [0; 1], A = [0 1; -k -delta] with
// k = alpha or g / l (Hurwitz for k, delta > 0), and the forcing's period 2 pi / omega as their
// lap. The read-out offset y0 places the state's range inside the study's domain ([0, L], or the
// box [0, L] x [0, W] for a read-out of both coordinates).
#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "rkhs/adaptive/lyapunov.hpp"
#include "rkhs/adaptive/plant.hpp"

namespace rkhs {

namespace {

std::vector<ParameterSpec> forcing_parameters(std::vector<ParameterSpec> parameters) {
  parameters.push_back(
      real_parameter("amplitude", 1.0, "forcing amplitude gamma (m/s^2 or rad/s^2)"));
  parameters.push_back(positive_parameter("omega", 1.2, "forcing frequency omega, rad/s"));
  return parameters;
}

/// The two-state forced oscillators above: q'' = -k q - delta q' + n(q) + f(y) + gamma cos(wt)
/// with a known nonlinearity n (zero for duffing) and the read-out y = c^T x + y0.
class ForcedOscillator : public Plant {
 public:
  /// The read-out y = C x + y0: C (p x 2) and y0 (p values).
  ForcedOscillator(double stiffness, double damping, double amplitude, double omega,
                   Eigen::MatrixXd readout, Eigen::VectorXd offset)
      : A_(2, 2),
        B_(2),
        C_(std::move(readout)),
        offset_(std::move(offset)),
        amplitude_(amplitude),
        omega_(omega) {
    A_ << 0, 1, -stiffness, -damping;
    B_ << 0, 1;
    require_hurwitz(A_);
  }
  /// The read-out of coordinate `coordinate` alone: y = x_coordinate + offset.
  static Eigen::MatrixXd coordinate_readout(Eigen::Index coordinate) {
    Eigen::MatrixXd c = Eigen::MatrixXd::Zero(1, 2);
    c(0, coordinate) = 1;
    return c;
  }
  const Eigen::MatrixXd& A() const noexcept override { return A_; }
  const Eigen::VectorXd& B() const noexcept override { return B_; }
  const Eigen::MatrixXd& readout() const noexcept override { return C_; }
  const Eigen::VectorXd& readout_offset() const noexcept override { return offset_; }
  double period() const noexcept override { return 2 * std::numbers::pi / omega_; }
  void known_dynamics(double t, const double* x, double* h, double* dh_dx,
                      double* dh_dt) const override {
    double slope = 0;
    h[0] = 0;
    h[1] = nonlinearity(x[0], slope) + amplitude_ * std::cos(omega_ * t);
    if (dh_dx) {
      dh_dx[0] = dh_dx[1] = dh_dx[3] = 0;
      dh_dx[2] = slope;
    }
    if (dh_dt) {
      dh_dt[0] = 0;
      dh_dt[1] = -amplitude_ * omega_ * std::sin(omega_ * t);
    }
  }

 protected:
  /// The known nonlinear part of the restoring force at position q, and its slope.
  virtual double nonlinearity(double q, double& slope) const noexcept {
    slope = 0;
    (void)q;
    return 0;
  }

 private:
  Eigen::MatrixXd A_;
  Eigen::VectorXd B_;
  Eigen::MatrixXd C_;
  Eigen::VectorXd offset_;
  double amplitude_, omega_;
};

class Duffing final : public ForcedOscillator {
 public:
  static PluginInfo info() {
    return {"duffing",
            "forced Duffing oscillator q'' + delta q' + alpha q = f(q + y0) + gamma cos(omega t), "
            "f an unknown stiffness law of the position; state [q, q']",
            forcing_parameters(
                {positive_parameter("alpha", 1.0, "linear stiffness alpha, 1/s^2"),
                 positive_parameter("delta", 0.5, "damping delta, 1/s"),
                 real_parameter("offset", 2.0,
                                "read-out offset y0: f is evaluated at y = q + y0 in the domain"),
                 choice_parameter("readout", "position",
                                  "what f is a function of: the position, y = q + y0 (a domain "
                                  "of d = 1), or the state, y = (q + y0, q' + y0') (d = 2)",
                                  {"position", "state"}),
                 real_parameter("velocity_offset", 2.0,
                                "readout = \"state\": y0', the offset of the velocity "
                                "coordinate y2 = q' + y0'")}),
            {{"dimension", "2"}, {"read-out", "y = q + y0, or (q + y0, q' + y0')"}}};
  }
  explicit Duffing(const ParameterSet& p)
      : ForcedOscillator(p.real("alpha"), p.real("delta"), p.real("amplitude"), p.real("omega"),
                         readout(p), offsets(p)) {}

 private:
  static bool of_state(const ParameterSet& p) { return p.choice("readout") == "state"; }
  static Eigen::MatrixXd readout(const ParameterSet& p) {
    return of_state(p) ? Eigen::MatrixXd::Identity(2, 2) : coordinate_readout(0);
  }
  static Eigen::VectorXd offsets(const ParameterSet& p) {
    if (!of_state(p)) return Eigen::VectorXd::Constant(1, p.real("offset"));
    Eigen::VectorXd y0(2);
    y0 << p.real("offset"), p.real("velocity_offset");
    return y0;
  }
};

class Pendulum final : public ForcedOscillator {
 public:
  static PluginInfo info() {
    return {"pendulum",
            "forced pendulum theta'' + (g/l) sin(theta) + c theta' = f(theta' + y0) + gamma "
            "cos(omega t), f an unknown friction law of the angular velocity; state "
            "[theta, theta']",
            forcing_parameters(
                {positive_parameter("length", 1.0, "pendulum length l, metres"),
                 positive_parameter("gravity", 9.81, "gravitational acceleration g, m/s^2"),
                 positive_parameter("damping", 0.5, "known viscous damping c, 1/s"),
                 real_parameter("offset", 2.0,
                                "read-out offset y0: f is evaluated at y = theta' + y0 in the "
                                "domain")}),
            {{"dimension", "2"}, {"read-out", "y = theta' + y0"}}};
  }
  explicit Pendulum(const ParameterSet& p)
      : ForcedOscillator(p.real("gravity") / p.real("length"), p.real("damping"),
                         p.real("amplitude"), p.real("omega"), coordinate_readout(1),
                         Eigen::VectorXd::Constant(1, p.real("offset"))),
        frequency_squared_(p.real("gravity") / p.real("length")) {}

 protected:
  // -(g/l) (sin(theta) - theta): the part of the gravity term beyond A's linearisation.
  double nonlinearity(double theta, double& slope) const noexcept override {
    slope = -frequency_squared_ * (std::cos(theta) - 1);
    return -frequency_squared_ * (std::sin(theta) - theta);
  }

 private:
  double frequency_squared_;
};

}  // namespace
}  // namespace rkhs

RKHS_REGISTER_PLANT(rkhs::Duffing)
RKHS_REGISTER_PLANT(rkhs::Pendulum)
