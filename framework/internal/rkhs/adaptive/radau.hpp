#pragma once
// Radau IIA of order 5: the 3-stage, L-stable, stiffly accurate collocation method (Hairer and
// Wanner, Solving ODEs II, Sec. IV.8), with the error estimate and the predictive (Gustafsson)
// step-size controller of RADAU5, as a stepping policy of drive_steps (stepping.hpp).
//
// The stage equations are solved by simplified Newton iterations in the transformed variables
// W = T^-1 Z, which split the 3m x 3m system into one real and one complex m x m system:
//   (mu_r / h I - J) dW_0 = ...,   (mu_c / h I - J) (dW_1 + i dW_2) = ...
// J is the Jacobian at the start of the step, recomputed every step (the problems here have a
// cheap structured Jacobian, rkhs/adaptive/coupled_structure.hpp). The state is a matrix of
// `columns` columns that share steps: one trajectory (columns = 1), or the columns of the lap
// map (the monodromy matrix and the forced orbit, rkhs/adaptive/lap_map.hpp); the error norm
// is the RMS over all entries.
//
// A RadauProblem P provides
//   Eigen::Index rows() const, columns() const;
//   void rhs(double t, const Eigen::MatrixXd& Z, Eigen::MatrixXd& dZ);   every column
//   void factor(double t, const Eigen::MatrixXd& Z, double real_shift,
//               std::complex<double> complex_shift);
//       J = J(t, Z) at the state Z the step starts from (a problem linear in Z ignores it);
//       factorises (real_shift I - J) and (complex_shift I - J)
//   void solve_real(Eigen::MatrixXd& R) const;       R <- (real_shift I - J)^-1 R, per column
//   void solve_complex(Eigen::MatrixXcd& R) const;   likewise with complex_shift

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>

#include "rkhs/adaptive/stepping.hpp"

namespace rkhs {

template <class P>
concept RadauProblem =
    requires(P& p, const P& cp, double t, const Eigen::MatrixXd& Z, Eigen::MatrixXd& dZ,
             Eigen::MatrixXcd& C, std::complex<double> shift) {
      { cp.rows() } -> std::convertible_to<Eigen::Index>;
      { cp.columns() } -> std::convertible_to<Eigen::Index>;
      p.rhs(t, Z, dZ);
      p.factor(t, Z, t, shift);
      cp.solve_real(dZ);
      cp.solve_complex(C);
    };

/// Radau IIA (order 5) on a RadauProblem. Counts its work in the problem's own counters.
template <RadauProblem Problem>
class RadauIIA5 {
 public:
  /// The real and complex eigenvalues mu of the inverse Butcher matrix: a step of size h
  /// factorises (mu / h I - J) for both (RadauProblem::factor).
  static inline const double mu_real =
      3 + std::cbrt(9.0) - std::cbrt(3.0);  // 3 + 3^(2/3) - 3^(1/3)
  static inline const std::complex<double> mu_complex{
      3 + 0.5 * (std::cbrt(3.0) - std::cbrt(9.0)),
      -0.5 * (std::pow(3.0, 5.0 / 6) + std::pow(3.0, 7.0 / 6))};

  RadauIIA5(Problem& problem, double atol, double rtol)
      : problem_(problem),
        atol_(atol),
        rtol_(rtol),
        newton_tolerance_(std::max(10 * std::numeric_limits<double>::epsilon() / rtol,
                                   std::min(0.03, std::sqrt(rtol)))),
        y_(Eigen::MatrixXd::Zero(problem.rows(), problem.columns())),
        f_(y_),
        y_new_(y_),
        stage_(y_),
        scale_(y_),
        error_(y_),
        ze_(y_),
        real_(y_),
        complex_(Eigen::MatrixXcd::Zero(y_.rows(), y_.cols())) {
    for (int i = 0; i < 3; ++i) {
      z_[i] = y_;
      w_[i] = y_;
      dw_[i] = y_;
      f_stage_[i] = y_;
      q_[i] = y_;
    }
  }

  double* state() { return y_.data(); }

  /// Forgets the collocation polynomial of the last step (its extrapolation starts the next
  /// Newton iteration) and the derivative at the current point: after a kink, or when the
  /// state was changed from outside.
  void reset() {
    have_polynomial_ = false;
    have_f_ = false;
    h_old_ = 0;
    error_old_ = 0;
  }

  std::size_t newton_iterations() const noexcept { return newton_iterations_; }

  StepOutcome try_step(double& t, double& dt) {
    const double h = dt;
    if (!have_f_) {
      problem_.rhs(t, y_, f_);
      have_f_ = true;
    }
    problem_.factor(t, y_, mu_real / h, mu_complex / h);
    // Starting values: the last step's collocation polynomial extrapolated, or zero.
    for (int i = 0; i < 3; ++i) {
      if (have_polynomial_) {
        const double x = (t + c[i] * h - t_old_) / h_old_;
        z_[i] = y_old_ - y_ + x * (q_[0] + x * (q_[1] + x * q_[2]));
      } else {
        z_[i].setZero();
      }
    }
    scale_.array() = atol_ + rtol_ * y_.array().abs();
    int iterations = 0;
    double rate = 0;
    const bool converged = solve_collocation(t, h, iterations, rate);
    if (!converged) {
      dt = 0.5 * h;
      rejected_last_ = true;
      have_polynomial_ = false;  // a diverged iteration: restart from zero
      return StepOutcome::rejected;
    }
    y_new_ = y_ + z_[2];
    // Error estimate (RADAU5): (mu_r / h I - J)^-1 (f(t, y) + sum_i e_i Z_i / h).
    ze_ = (e[0] * z_[0] + e[1] * z_[1] + e[2] * z_[2]) / h;
    error_ = f_ + ze_;
    problem_.solve_real(error_);
    scale_.array() = atol_ + rtol_ * y_.array().abs().max(y_new_.array().abs());
    double error = rms(error_);
    if (rejected_last_ && error > 1) {
      // One more filtering through the stiff part after a rejection (Hairer's remedy for
      // overestimated errors of stiff components).
      stage_ = y_ + error_;
      problem_.rhs(t, stage_, error_);
      error_ += ze_;
      problem_.solve_real(error_);
      error = rms(error_);
    }
    const double safety = 0.9 * (2 * max_newton + 1) / (2 * max_newton + iterations);
    if (!(error <= 1)) {
      const double factor = std::isfinite(error) ? predicted_factor(h, error) : 0.1;
      dt = h * std::max(min_factor, safety * factor);
      rejected_last_ = true;
      return StepOutcome::rejected;
    }
    // Accepted: the collocation polynomial of this step, for the next starting values.
    for (int k = 0; k < 3; ++k) q_[k] = p[0][k] * z_[0] + p[1][k] * z_[1] + p[2][k] * z_[2];
    y_old_ = y_;
    t_old_ = t;
    const double factor = std::min(max_factor, safety * predicted_factor(h, error));
    y_ = y_new_;
    t += h;
    problem_.rhs(t, y_, f_);
    h_old_ = h;
    error_old_ = error;
    have_polynomial_ = true;
    rejected_last_ = false;
    dt = h * factor;
    return StepOutcome::accepted;
  }

 private:
  // The method's constants (Hairer and Wanner; the eigenvalues mu of the inverse of the
  // Butcher matrix, the transformation T that diagonalises it, the error weights e and the
  // coefficients p of the collocation polynomial).
  static constexpr double sqrt6 = 2.449489742783178098197284;
  static constexpr double c[3] = {(4 - sqrt6) / 10, (4 + sqrt6) / 10, 1.0};
  static constexpr double e[3] = {(-13 - 7 * sqrt6) / 3, (-13 + 7 * sqrt6) / 3, -1.0 / 3};
  static constexpr double t_matrix[3][3] = {
      {0.09443876248897524, -0.14125529502095421, 0.03002919410514742},
      {0.25021312296533332, 0.20412935229379994, -0.38294211275726192},
      {1.0, 1.0, 0.0}};
  static constexpr double t_inverse[3][3] = {
      {4.17871859155190428, 0.32768282076106237, 0.52337644549944951},
      {-4.17871859155190428, -0.32768282076106237, 0.47662355450055044},
      {0.50287263494578682, -2.57192694985560522, 0.59603920482822492}};
  static constexpr double p[3][3] = {
      {13.0 / 3 + 7 * sqrt6 / 3, -23.0 / 3 - 22 * sqrt6 / 3, 10.0 / 3 + 5 * sqrt6},
      {13.0 / 3 - 7 * sqrt6 / 3, -23.0 / 3 + 22 * sqrt6 / 3, 10.0 / 3 - 5 * sqrt6},
      {1.0 / 3, -8.0 / 3, 10.0 / 3}};
  static constexpr int max_newton = 6;
  static constexpr double min_factor = 0.2, max_factor = 10;

  double rms(const Eigen::MatrixXd& v) const {
    return std::sqrt((v.array() / scale_.array()).square().sum() / static_cast<double>(v.size()));
  }

  // Gustafsson's predictive controller, as in RADAU5.
  double predicted_factor(double h, double error) const {
    double multiplier = 1;
    if (h_old_ > 0 && error_old_ > 0 && error > 0)
      multiplier = h / h_old_ * std::pow(error_old_ / error, 0.25);
    return std::min(1.0, multiplier) * std::pow(std::max(error, 1e-300), -0.25);
  }

  // Simplified Newton iterations for the stage values Z (z_[0..2]); true when converged.
  bool solve_collocation(double t, double h, int& iterations, double& rate) {
    for (int i = 0; i < 3; ++i)
      w_[i] = t_inverse[i][0] * z_[0] + t_inverse[i][1] * z_[1] + t_inverse[i][2] * z_[2];
    double norm_old = -1;
    rate = 0;
    for (int k = 0; k < max_newton; ++k) {
      iterations = k + 1;
      ++newton_iterations_;
      for (int i = 0; i < 3; ++i) {
        stage_ = y_ + z_[i];
        problem_.rhs(t + c[i] * h, stage_, f_stage_[i]);
        if (!f_stage_[i].allFinite()) return false;
      }
      real_ = t_inverse[0][0] * f_stage_[0] + t_inverse[0][1] * f_stage_[1] +
              t_inverse[0][2] * f_stage_[2] - (mu_real / h) * w_[0];
      complex_.real() = t_inverse[1][0] * f_stage_[0] + t_inverse[1][1] * f_stage_[1] +
                        t_inverse[1][2] * f_stage_[2];
      complex_.imag() = t_inverse[2][0] * f_stage_[0] + t_inverse[2][1] * f_stage_[1] +
                        t_inverse[2][2] * f_stage_[2];
      // - (mu_c / h) (W_1 + i W_2)
      const std::complex<double> m = mu_complex / h;
      complex_.real() -= m.real() * w_[1] - m.imag() * w_[2];
      complex_.imag() -= m.real() * w_[2] + m.imag() * w_[1];
      problem_.solve_real(real_);
      problem_.solve_complex(complex_);
      dw_[0] = real_;
      dw_[1] = complex_.real();
      dw_[2] = complex_.imag();
      double sum = 0;
      for (int i = 0; i < 3; ++i) sum += (dw_[i].array() / scale_.array()).square().sum();
      const double norm = std::sqrt(sum / (3.0 * static_cast<double>(y_.size())));
      if (norm_old >= 0) rate = norm / norm_old;
      if (norm_old >= 0 &&
          (rate >= 1 || std::pow(rate, max_newton - k) / (1 - rate) * norm > newton_tolerance_))
        return false;
      for (int i = 0; i < 3; ++i) w_[i] += dw_[i];
      for (int i = 0; i < 3; ++i)
        z_[i] = t_matrix[i][0] * w_[0] + t_matrix[i][1] * w_[1] + t_matrix[i][2] * w_[2];
      if (norm == 0 || (norm_old >= 0 && rate / (1 - rate) * norm < newton_tolerance_))
        return true;
      norm_old = norm;
    }
    return false;
  }

  Problem& problem_;
  double atol_, rtol_, newton_tolerance_;
  Eigen::MatrixXd y_, f_, y_new_, y_old_, stage_, scale_, error_, ze_, real_;
  Eigen::MatrixXcd complex_;
  Eigen::MatrixXd z_[3], w_[3], dw_[3], f_stage_[3], q_[3];
  double t_old_ = 0, h_old_ = 0, error_old_ = 0;
  bool have_polynomial_ = false, have_f_ = false, rejected_last_ = false;
  std::size_t newton_iterations_ = 0;
};

}  // namespace rkhs
