#include "rkhs/rates/corrected_fit.hpp"

#include <Eigen/Dense>
#include <boost/math/distributions/students_t.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace rkhs {
namespace {

constexpr double lowest_order = 0.05, highest_order = 10.0;
constexpr std::size_t minimum_points = 6;

using Vector4 = Eigen::Vector4d;

// ln y = c + p (u - u_mean) + ln(1 + D e^{-q w}),  w = refinement coordinate, 0 at the finest.
struct Model {
  const Eigen::VectorXd& centred_u;
  const Eigen::VectorXd& w;
  const Eigen::VectorXd& v;

  // Residuals v - model; false when 1 + D e^{-q w} <= 0 somewhere.
  bool residuals(const Vector4& theta, Eigen::VectorXd& r) const {
    for (Eigen::Index i = 0; i < v.size(); ++i) {
      const double g = 1.0 + theta[2] * std::exp(-theta[3] * w[i]);
      if (!(g > 0.0)) return false;
      r[i] = v[i] - (theta[0] + theta[1] * centred_u[i] + std::log(g));
    }
    return true;
  }
  void jacobian(const Vector4& theta, Eigen::MatrixXd& j) const {
    for (Eigen::Index i = 0; i < v.size(); ++i) {
      const double e = std::exp(-theta[3] * w[i]), g = 1.0 + theta[2] * e;
      j(i, 0) = 1.0;
      j(i, 1) = centred_u[i];
      j(i, 2) = e / g;
      j(i, 3) = -theta[2] * w[i] * e / g;
    }
  }
};

}  // namespace

std::optional<CorrectedRateFit> fit_power_law_corrected(std::span<const double> x,
                                                        std::span<const double> y,
                                                        bool refines_upward, double confidence) {
  if (x.size() != y.size())
    throw std::invalid_argument("fit_power_law_corrected: x and y differ in size");
  if (!(confidence > 0.0 && confidence < 1.0))
    throw std::invalid_argument("fit_power_law_corrected: confidence must lie in (0, 1)");
  const auto m = static_cast<Eigen::Index>(x.size());
  if (x.size() < minimum_points) return std::nullopt;
  Eigen::VectorXd u(m), v(m);
  for (Eigen::Index i = 0; i < m; ++i) {
    if (!(x[i] > 0.0 && std::isfinite(x[i]) && y[i] > 0.0 && std::isfinite(y[i])))
      return std::nullopt;
    u[i] = std::log(x[i]);
    v[i] = std::log(y[i]);
  }
  const double direction = refines_upward ? 1.0 : -1.0;
  const double finest = refines_upward ? u.maxCoeff() : u.minCoeff();
  const Eigen::VectorXd w = direction * (u.array() - finest).matrix();  // <= 0, 0 at the finest
  const double u_mean = u.mean();
  const Eigen::VectorXd centred_u = (u.array() - u_mean).matrix();
  if (!(centred_u.squaredNorm() > 0.0)) return std::nullopt;
  const Model model{centred_u, w, v};

  // The straight line on the same points.
  const double slope = centred_u.dot(v) / centred_u.squaredNorm();
  const double line_sse = ((v.array() - v.mean()) - slope * centred_u.array()).matrix().squaredNorm();

  // Start: q on a log grid, the linearised model ln(1 + z) ~ z solved for (c, p, D) at each.
  Vector4 theta;
  double best = std::numeric_limits<double>::infinity();
  Eigen::MatrixXd design(m, 3);
  constexpr int grid = 120;
  for (int k = 0; k <= grid; ++k) {
    const double q = lowest_order * std::pow(highest_order / lowest_order, double(k) / grid);
    design.col(0).setOnes();
    design.col(1) = centred_u;
    design.col(2) = (-q * w.array()).exp().matrix();
    const Eigen::Vector3d c = design.colPivHouseholderQr().solve(v);
    const double sse = (v - design * c).squaredNorm();
    if (sse < best) {
      best = sse;
      theta << c[0], c[1], c[2], q;
    }
  }
  // Keep the start feasible: 1 + D e^{-q w} > 0 at every point.
  Eigen::VectorXd r(m), trial_r(m);
  for (int shrink = 0; !model.residuals(theta, r); ++shrink) {
    if (shrink == 60) return std::nullopt;
    theta[2] *= 0.5;
  }
  double sse = r.squaredNorm();

  // Levenberg-Marquardt (Marquardt's scaling by diag(J^T J)).
  Eigen::MatrixXd j(m, 4);
  double lambda = 1e-3;
  for (int iteration = 0; iteration < 200; ++iteration) {
    model.jacobian(theta, j);
    const Eigen::Matrix4d normal = j.transpose() * j;
    const Vector4 gradient = j.transpose() * r;
    Eigen::Matrix4d damped = normal;
    damped.diagonal() += lambda * normal.diagonal().cwiseMax(1e-300);
    const Vector4 step = damped.ldlt().solve(gradient);
    const Vector4 next = theta + step;
    if (next[3] > 0.0 && model.residuals(next, trial_r) && trial_r.squaredNorm() <= sse) {
      const bool settled = step.norm() <= 1e-12 * (1.0 + theta.norm()) ||
                           sse - trial_r.squaredNorm() <= 1e-15 * sse;
      theta = next;
      r = trial_r;
      sse = r.squaredNorm();
      lambda = std::max(lambda * 0.3, 1e-12);
      if (settled) break;
    } else {
      lambda *= 10.0;
      if (lambda > 1e12) break;
    }
  }
  const double q = theta[3];
  if (!(q >= lowest_order && q <= highest_order)) return std::nullopt;

  model.jacobian(theta, j);
  const Eigen::Matrix4d normal = j.transpose() * j;
  const Eigen::FullPivLU<Eigen::Matrix4d> lu(normal);
  if (!lu.isInvertible() || lu.rcond() < 1e-14) return std::nullopt;
  const Eigen::Matrix4d inverse = lu.inverse();
  const double dof = static_cast<double>(m - 4);

  CorrectedRateFit out;
  out.order = q;
  out.correction = theta[2];
  out.sse = sse;
  out.line_sse = line_sse;
  const double floor = static_cast<double>(m) * 1e-20;  // exact series: a finite ratio
  // AICc (Hurvich and Tsai): 2k + 2k(k + 1) / (m - k - 1) for k parameters, here 4 against 2.
  const double points = static_cast<double>(m);
  auto penalty = [&](double k) { return 2.0 * k + 2.0 * k * (k + 1.0) / (points - k - 1.0); };
  out.advantage = points * std::log(std::max(line_sse, floor) / std::max(sse, floor)) -
                  (penalty(4.0) - penalty(2.0));
  RateFit& fit = out.fit;
  fit.model = RateModel::power_law;
  fit.rate = theta[1];
  fit.intercept = theta[0] - theta[1] * u_mean;
  fit.confidence = confidence;
  fit.points = x.size();
  for (std::size_t i = 0; i < x.size(); ++i) fit.used.push_back(i);
  fit.residual_std = std::sqrt(sse / dof);
  fit.std_error = std::sqrt(std::max(0.0, sse / dof * inverse(1, 1)));
  const boost::math::students_t t(dof);
  const double half_width = boost::math::quantile(t, 0.5 + 0.5 * confidence) * fit.std_error;
  fit.ci_low = fit.rate - half_width;
  fit.ci_high = fit.rate + half_width;
  const double sst = (v.array() - v.mean()).matrix().squaredNorm();
  fit.r_squared = sst > 0.0 ? 1.0 - sse / sst : std::numeric_limits<double>::quiet_NaN();
  if (!std::isfinite(fit.std_error)) return std::nullopt;
  return out;
}

}  // namespace rkhs
