// Built-in plant vehicle_surface (docs/model.md section 18): the quarter car of the paper's
// Section 5 whose wheel follows a closed path w(t) in the plane at a constant speed, over an
// unknown road surface f(u, v) on the study's domain (a box or torus of d = 2).
//
// State x = [x1', x1, x2', x2, p1, p2]: the quarter car's and the wheel's position p, with
//
//   [x1', x1, x2', x2]' = A_qc [x1', x1, x2', x2] + B_qc f(p)
//   p'                  = -lambda (p - w(t)) + w'(t)
//
// so A = diag(A_qc, -lambda I) is Hurwitz, h(t, x) = [0; lambda w(t) + w'(t)] is known, and
// p(t) = w(t) from p(0) = w(0) (a deviation decays at the rate lambda). The read-out is y = p:
// f is learnt under the path. B = [B_qc; 0, 0], so the learning sees the quarter car alone.
//
// The path is a closed polyline through waypoints, driven at `speed`: either `waypoints`
// ("u v; u v; ...": rows of parse_matrix) or `passes` at lateral positions v_1, ..., v_K
// ("0.25; 0.75") along u from `pass_start` to `pass_start + pass_length`, a raster: out along
// v_1, across to v_2 at the far end, back along v_2, and so on, closing back to the first
// waypoint (across the near end after an even number of passes, diagonally after an odd one).
// One lap is one traversal (period = perimeter / speed).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "rkhs/adaptive/lyapunov.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/plants/quarter_car.hpp"

namespace rkhs {

namespace {

class VehicleSurface final : public Plant {
 public:
  static PluginInfo info() {
    auto parameters = quarter_car::parameters();
    parameters.push_back(positive_parameter("speed", 0.1, "speed along the path, m/s"));
    parameters.push_back(text_parameter(
        "waypoints", "",
        "the path: a closed polyline through these points of the plane, 'u v' rows separated by "
        "';' (e.g. \"0 0.25; 1 0.25; 1 0.75; 0 0.75\"); or empty, and passes"));
    parameters.push_back(text_parameter(
        "passes", "",
        "the path as a raster: passes along u at these lateral positions v, separated by ';' "
        "(e.g. \"0.25; 0.75\"), from pass_start to pass_start + pass_length and back"));
    parameters.push_back(real_parameter("pass_start", 0.0, "u where the passes start, m"));
    parameters.push_back(positive_parameter("pass_length", 1.0, "length of each pass, m"));
    parameters.push_back(positive_parameter(
        "tracking_rate", 1.0,
        "lambda, 1/s: the wheel's position p obeys p' = -lambda (p - w(t)) + w'(t), which keeps "
        "A Hurwitz; p = w(t) from the start"));
    return {"vehicle_surface",
            "quarter car whose wheel follows a closed path w(t) in the plane over an unknown "
            "surface f(u, v) (d = 2); state [x1', x1, x2', x2, p1, p2], read-out y = p",
            parameters,
            {{"dimension", "6"}, {"read-out", "y = (p1, p2), the wheel's position"}}};
  }

  explicit VehicleSurface(const ParameterSet& p)
      : speed_(p.real("speed")), lambda_(p.real("tracking_rate")) {
    Eigen::MatrixXd car_A;
    Eigen::VectorXd car_B;
    quarter_car::system(p, car_A, car_B);
    A_ = Eigen::MatrixXd::Zero(6, 6);
    A_.topLeftCorner(4, 4) = car_A;
    A_.bottomRightCorner(2, 2) = -lambda_ * Eigen::Matrix2d::Identity();
    B_ = Eigen::VectorXd::Zero(6);
    B_.head(4) = car_B;
    C_ = Eigen::MatrixXd::Zero(2, 6);
    C_(0, 4) = C_(1, 5) = 1;
    offset_ = Eigen::VectorXd::Zero(2);
    require_hurwitz(A_);
    waypoints_ = path(p);
    const Eigen::Index count = waypoints_.rows();
    cumulative_.assign(static_cast<std::size_t>(count) + 1, 0.0);
    for (Eigen::Index k = 0; k < count; ++k) {
      const double length = (waypoints_.row((k + 1) % count) - waypoints_.row(k)).norm();
      if (!(length > 0))
        throw ParameterError(
            p.text("waypoints").empty() ? "passes" : "waypoints",
            fmt::format("waypoints {} and {} of the path coincide", k + 1, (k + 1) % count + 1));
      cumulative_[static_cast<std::size_t>(k) + 1] =
          cumulative_[static_cast<std::size_t>(k)] + length;
    }
    x0_ = Eigen::VectorXd::Zero(6);
    x0_.tail(2) = waypoints_.row(0).transpose();
  }

  const Eigen::MatrixXd& A() const noexcept override { return A_; }
  const Eigen::VectorXd& B() const noexcept override { return B_; }
  const Eigen::MatrixXd& readout() const noexcept override { return C_; }
  const Eigen::VectorXd& readout_offset() const noexcept override { return offset_; }
  double period() const noexcept override { return cumulative_.back() / speed_; }
  const Eigen::VectorXd& initial_state() const noexcept override { return x0_; }

  void known_dynamics(double t, const double* x, double* h, double* dh_dx,
                      double* dh_dt) const override {
    (void)x;
    double w[2], dw[2];
    position(t, w, dw);
    for (int i = 0; i < 4; ++i) h[i] = 0;
    h[4] = lambda_ * w[0] + dw[0];
    h[5] = lambda_ * w[1] + dw[1];
    if (dh_dx)
      for (int i = 0; i < 36; ++i) dh_dx[i] = 0;
    if (dh_dt) {  // w'' = 0 within a segment (the right-hand value at a corner)
      for (int i = 0; i < 4; ++i) dh_dt[i] = 0;
      dh_dt[4] = lambda_ * dw[0];
      dh_dt[5] = lambda_ * dw[1];
    }
  }

 private:
  /// The waypoints (rows u, v) from `waypoints` or `passes`.
  static Eigen::MatrixXd path(const ParameterSet& p) {
    const std::string& written = p.text("waypoints");
    const std::string& passes = p.text("passes");
    if (written.empty() == passes.empty())
      throw ParameterError(written.empty() ? "waypoints" : "passes",
                           "give the path as exactly one of waypoints (\"u v; u v; ...\") and "
                           "passes (lateral positions \"v1; v2; ...\")");
    if (!written.empty()) {
      Eigen::MatrixXd points;
      try {
        points = parse_matrix(written);
      } catch (const std::invalid_argument& e) {
        throw ParameterError("waypoints", e.what());
      }
      if (points.cols() != 2 || points.rows() < 2)
        throw ParameterError("waypoints",
                             fmt::format("expected at least 2 rows of 2 coordinates 'u v', found "
                                         "{} x {}",
                                         points.rows(), points.cols()));
      return points;
    }
    Eigen::MatrixXd lateral;
    try {
      lateral = parse_matrix(passes);
    } catch (const std::invalid_argument& e) {
      throw ParameterError("passes", e.what());
    }
    if (lateral.cols() != 1)
      throw ParameterError("passes", fmt::format("expected lateral positions separated by ';', "
                                                 "found a {} x {} matrix",
                                                 lateral.rows(), lateral.cols()));
    const double from = p.real("pass_start"), to = from + p.real("pass_length");
    Eigen::MatrixXd points(2 * lateral.rows(), 2);
    for (Eigen::Index k = 0; k < lateral.rows(); ++k) {
      const bool out = k % 2 == 0;  // out along u on even passes, back on odd ones
      points.row(2 * k) << (out ? from : to), lateral(k, 0);
      points.row(2 * k + 1) << (out ? to : from), lateral(k, 0);
    }
    return points;
  }

  /// w(t) and w'(t) on the closed polyline (the segment that starts at or before the arc
  /// length v t, modulo the perimeter).
  void position(double t, double* w, double* dw) const noexcept {
    const double perimeter = cumulative_.back();
    double u = std::fmod(speed_ * t, perimeter);
    if (u < 0) u += perimeter;
    const auto count = static_cast<std::size_t>(waypoints_.rows());
    const auto after = std::upper_bound(cumulative_.begin(), cumulative_.end(), u);
    const std::size_t k =
        std::min(count - 1, static_cast<std::size_t>(after - cumulative_.begin()) - 1);
    const auto from = static_cast<Eigen::Index>(k), to = static_cast<Eigen::Index>((k + 1) % count);
    const double length = cumulative_[k + 1] - cumulative_[k];
    const double along = (u - cumulative_[k]) / length;
    for (int a = 0; a < 2; ++a) {
      const double start = waypoints_(from, a), end = waypoints_(to, a);
      w[a] = start + along * (end - start);
      dw[a] = speed_ * (end - start) / length;
    }
  }

  Eigen::MatrixXd A_;
  Eigen::VectorXd B_;
  Eigen::MatrixXd C_;
  Eigen::VectorXd offset_;
  Eigen::VectorXd x0_;
  double speed_, lambda_;
  Eigen::MatrixXd waypoints_;
  std::vector<double> cumulative_;  // arc length at each waypoint, the perimeter last
};

}  // namespace
}  // namespace rkhs

RKHS_REGISTER_PLANT(rkhs::VehicleSurface)
