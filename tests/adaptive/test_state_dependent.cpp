// State-dependent plants (docs/model.md section 18): f of the read-out y = C x + y0.
//   - the exact Jacobian and dF/dt of the coupled system against differences of its rhs, for
//     read-outs of one coordinate and of two (f on a box in R^2);
//   - the visited set in d > 1 (the neighbourhood of the sampled read-outs' polyline) against
//     distances worked out by hand;
//   - the plant's own trajectory against the oscillators' equations integrated independently;
//   - with f in H_n and an orbit that sweeps Omega, alpha -> alpha* and V does not increase;
//     an orbit over half of Omega leaves directions unexcited and says so;
//   - study files that ask a state-dependent plant for what it cannot do.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <random>
#include <string>

#include "plugins/kernels/kernel_test_support.hpp"
#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/adaptive/lyapunov.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/adaptive/state_dependent.hpp"
#include "rkhs/approx/gram_solver.hpp"
#include "rkhs/study/study.hpp"
#include "study_support.hpp"

using namespace rkhs;

namespace {

std::unique_ptr<Plant> make_plant(const std::string& name,
                                  std::map<std::string, ParameterValue> parameters) {
  const auto* entry = plant_registry().find(name);
  REQUIRE(entry);
  return entry->factory(ParameterSet::resolve(entry->info.parameters, parameters));
}

std::unique_ptr<Integrator> make_integrator(const std::string& name,
                                            std::map<std::string, ParameterValue> parameters) {
  const auto* entry = integrator_registry().find(name);
  REQUIRE(entry);
  return entry->factory(ParameterSet::resolve(entry->info.parameters, parameters));
}

const Domain interval{3.6, false};

struct KernelCase {
  std::string name;
  std::map<std::string, ParameterValue> parameters;
};

using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// The system's Jacobian J and dF/dt at (z, t), and how far each lies from central differences
/// of its rhs with step `step` (largest absolute entry of the difference).
struct DerivativeCheck {
  RowMajorMatrix J;
  Eigen::VectorXd dfdt;
  double jacobian_gap = 0, time_gap = 0;
};
DerivativeCheck check_derivatives(const AdaptiveSystem& system, const Eigen::VectorXd& z, double t,
                                  double step) {
  const Eigen::Index m = system.dimension();
  DerivativeCheck out{RowMajorMatrix(m, m), Eigen::VectorXd(m)};
  system.jacobian(z.data(), out.J.data(), t, out.dfdt.data());
  Eigen::VectorXd up(m), down(m);
  Eigen::MatrixXd difference(m, m);
  for (Eigen::Index j = 0; j < m; ++j) {
    Eigen::VectorXd z_up = z, z_down = z;
    z_up(j) += step;
    z_down(j) -= step;
    system.rhs(z_up.data(), up.data(), t);
    system.rhs(z_down.data(), down.data(), t);
    difference.col(j) = (up - down) / (2 * step);
  }
  out.jacobian_gap = (Eigen::MatrixXd(out.J) - difference).cwiseAbs().maxCoeff();
  system.rhs(z.data(), up.data(), t + step);
  system.rhs(z.data(), down.data(), t - step);
  out.time_gap = ((up - down) / (2 * step) - out.dfdt).cwiseAbs().maxCoeff();
  return out;
}

/// The error message of parsing `text` as the study file `file`, or "no error".
std::string study_error(const std::string& text, const std::string& file) {
  try {
    parse_study(text, file);
  } catch (const StudyError& e) {
    return e.what();
  }
  return "no error";
}

/// `text` with the first `from` replaced by `to` (which must be there).
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}

// f(y) = -(y - 1.8)^3 (the Duffing stiffness -q^3 for y0 = 1.8) and its slope.
const std::function<double(double)> cubic = [](double y) { return -std::pow(y - 1.8, 3); };
const std::function<double(double)> cubic_slope = [](double y) {
  return -3 * std::pow(y - 1.8, 2);
};

/// The coupled system of a state-dependent trial: `plant`, Q = I, n uniform centres on
/// [0, 3.6], the rkhs law's Gamma^-1 G^-1 or the gradient law's Gamma^-1 I, and f, f'.
struct System {
  System(std::unique_ptr<Plant> plant_, const std::string& kernel_name,
         std::map<std::string, ParameterValue> kernel_parameters, std::size_t n, bool rkhs_law,
         const std::function<double(double)>& f, const std::function<double(double)>& slope)
      : plant(std::move(plant_)),
        kernel(test::make_registered_kernel(kernel_name, kernel_parameters, interval)),
        road(f),
        road_slope(slope) {
    for (std::size_t i = 0; i < n; ++i)
      centres.push_back(interval.length * static_cast<double>(i) / static_cast<double>(n - 1));
    const Eigen::Index d = plant->A().rows();
    P = solve_lyapunov(plant->A(), Eigen::MatrixXd::Identity(d, d)).P;
    const Eigen::MatrixXd identity =
        Eigen::MatrixXd::Identity(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
    map = rkhs_law ? Eigen::MatrixXd(GramSolver(kernel->gram(centres), {}).solve(identity) / 0.1)
                   : Eigen::MatrixXd(identity / 0.1);
    basis = kernel->basis(centres);
    system =
        std::make_unique<AdaptiveSystem>(plant->A(), plant->B(), P, *basis, map, road, road_slope,
                                         interval, 1.0, learning_signal_for(*kernel));
    system->set_state_readout(*plant);
  }
  std::unique_ptr<Plant> plant;
  std::unique_ptr<AnyKernel> kernel;
  std::vector<double> centres;
  Eigen::MatrixXd P, map;
  std::unique_ptr<KernelBasis> basis;
  std::function<double(double)> road, road_slope;
  std::unique_ptr<AdaptiveSystem> system;
};

}  // namespace

TEST_CASE("a state-dependent system's Jacobian and dF/dt are the derivatives of its rhs",
          "[adaptive][state]") {
  const std::vector<KernelCase> kernels{{"wendland", {{"k", std::int64_t{2}}, {"radius", 0.9}}},
                                        {"gaussian", {{"sigma", 0.4}}},
                                        {"matern", {}}};
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (const std::string plant_name : {"duffing", "pendulum"})
    for (const auto& kernel : kernels)
      for (const bool rkhs_law : {true, false}) {
        INFO(plant_name << " " << kernel.name << (rkhs_law ? " rkhs" : " gradient"));
        System trial(make_plant(plant_name, {{"offset", 1.8}, {"amplitude", 1.5}}), kernel.name,
                     kernel.parameters, 9, rkhs_law, cubic, cubic_slope);
        const AdaptiveSystem& system = *trial.system;
        const Eigen::Index m = system.dimension();
        for (int sample = 0; sample < 5; ++sample) {
          Eigen::VectorXd z(m);
          for (Eigen::Index i = 0; i < m; ++i) z(i) = unit(random);
          const double t = 3.0 + unit(random);
          // Central differences, step 1e-6: truncation ~1e-12 |F'''|, round-off ~1e-10 |F|.
          const auto check = check_derivatives(system, z, t, 1e-6);
          const double scale = std::max(1.0, check.J.cwiseAbs().maxCoeff());
          CHECK(check.jacobian_gap <= 1e-6 * scale);
          // The read-out couples x to alpha': the difference sees it, so the check is not empty.
          CHECK(check.J.block(2 * 2, 0, m - 4, 1).cwiseAbs().maxCoeff() > 0);
          CHECK(check.time_gap <= 1e-6 * scale);
        }
        // The Jacobian in t alone and the structured linearisation do not exist here.
        Eigen::MatrixXd J(m, m);
        CHECK_THROWS_AS(system.jacobian_matrix(0.0, J.data()), std::logic_error);
        CoupledLinearization linearization;
        CHECK_THROWS_AS(system.linearize(0.0, linearization), std::logic_error);
      }
}

TEST_CASE("the plant's trajectory in the coupled system is the oscillator's own",
          "[adaptive][state]") {
  // The plant's x does not depend on the estimator: integrated within the coupled system by
  // radau5 (exact Jacobian, dense stage solves), rodas4 and dopri5, x(T) must be what the
  // oscillator's equation gives, here by classical RK4 at h = 1e-4 written out below.
  struct Oscillator {
    std::string plant;
    std::function<double(double, double, double)> acceleration;  // q'' (t, q, q')
  };
  const double gamma = 1.5, omega = 1.2;
  const std::vector<Oscillator> oscillators{
      {"duffing", [&](double t, double q,
                      double v) { return -q - 0.5 * v - q * q * q + gamma * std::cos(omega * t); }},
      {"pendulum", [&](double t, double q, double v) {
         return -9.81 * std::sin(q) - 0.5 * v + cubic(v + 1.8) + gamma * std::cos(omega * t);
       }}};
  const double final_time = 10.0;
  for (const auto& oscillator : oscillators) {
    // Independent: q'' = acceleration(t, q, q') from rest.
    double q = 0, v = 0, t = 0;
    const double h = 1e-4;
    for (int k = 0; k < static_cast<int>(final_time / h + 0.5); ++k, t = k * h) {
      const double k1q = v, k1v = oscillator.acceleration(t, q, v);
      const double k2q = v + h / 2 * k1v,
                   k2v = oscillator.acceleration(t + h / 2, q + h / 2 * k1q, k2q);
      const double k3q = v + h / 2 * k2v,
                   k3v = oscillator.acceleration(t + h / 2, q + h / 2 * k2q, k3q);
      const double k4q = v + h * k3v, k4v = oscillator.acceleration(t + h, q + h * k3q, k4q);
      q += h / 6 * (k1q + 2 * k2q + 2 * k3q + k4q);
      v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
    }
    for (const std::string integrator_name : {"radau5", "rodas4", "dopri5"}) {
      INFO(oscillator.plant << " with " << integrator_name);
      System trial(make_plant(oscillator.plant, {{"offset", 1.8}, {"amplitude", gamma}}),
                   "wendland", {{"k", std::int64_t{1}}, {"radius", 0.9}}, 12, true, cubic,
                   cubic_slope);
      const auto integrator = make_integrator(integrator_name, {{"rtol", 1e-10}, {"atol", 1e-12}});
      Eigen::VectorXd z = Eigen::VectorXd::Zero(trial.system->dimension());
      const std::vector<double> times{0.0, final_time};
      integrator->integrate(*trial.system, z, times, [](std::size_t, const double*) {});
      CHECK(z(0) == Approx(q).margin(1e-7));
      CHECK(z(1) == Approx(v).margin(1e-7));
      // The estimator learnt something: xhat follows x, alpha moved.
      CHECK(z.tail(12).norm() > 0);
    }
  }
}

namespace {

// A Duffing oscillator learning f on [0, 3.6] with 8 Wendland sections (k = 1, radius 0.5) and
// the rkhs law (Gamma = 0.01) over 300 forcing periods, forcing amplitude `amplitude`; `road`
// "target" or "projection".
std::string duffing_study(const std::string& amplitude, const std::string& road,
                          const std::string& extra = "") {
  return R"([study]
name = "duffing_test"
kind = "adaptive"
evaluation_points = 1024
metrics = ["coefficient_error", "lyapunov_max_increase", "lyapunov_ratio", "pe_level",
           "unexcited_dimension", "path_l2_error", "off_path_l2_error", "l2_error",
           "final_state_error"]
[domain]
length = 3.6
periodic = false
[grid]
n = [8]
[[kernel]]
name = "wendland"
k = 1
radius = 0.5
[[target]]
name = "expression"
f = "-(s - 1.8)^3"
[[plant]]
name = "duffing"
offset = 1.8
amplitude = )" +
         amplitude +
         R"(
[[law]]
name = "rkhs"
gamma = 1e-2
[[integrator]]
name = "dopri5"
rtol = 1e-9
atol = 1e-11
[adaptive]
laps = 300
samples_per_lap = 100
road = ")" +
         road + "\"\n" + extra;
}

}  // namespace

TEST_CASE("with f in H_n and an orbit over Omega, alpha converges to alpha* and V never grows",
          "[adaptive][state]") {
  const auto swept = test::run_study_text(duffing_study("2.0", "projection"));
  CHECK(swept.metric(0, "unexcited_dimension") == 0);
  CHECK(swept.metric(0, "pe_level") > 1e-3);
  // Exponential convergence (pe_level = 0.033): to round-off in 300 forcing periods.
  CHECK(swept.metric(0, "coefficient_error") < 1e-10);
  // V' = -e^T Q e / 2 <= 0: V grows only by the integration's error.
  CHECK(swept.metric(0, "lyapunov_max_increase") < 1e-9);
  CHECK(swept.metric(0, "lyapunov_ratio") < 1e-20);
  CHECK(swept.metric(0, "final_state_error") < 1e-10);
  const auto& swept_flags = swept.results[0].flags;
  CHECK(std::count(swept_flags.begin(), swept_flags.end(), "not_persistently_excited") == 0);

  // Over half of Omega the outer sections never see the orbit (their supports end 0.5 from
  // their centres at 0, 0.51, 3.09 and 3.6; the orbit stays in [0.96, 2.64]): they are
  // unexcited and their coefficients never move from 0.
  const auto half = test::run_study_text(duffing_study("0.5", "projection"));
  CHECK(half.metric(0, "unexcited_dimension") == 2);
  CHECK(half.metric(0, "pe_level") == 0);
  const auto& flags = half.results[0].flags;
  CHECK(std::count(flags.begin(), flags.end(), "not_persistently_excited") == 1);
  CHECK(half.metric(0, "coefficient_error") > 0.1);
  CHECK(half.metric(0, "path_l2_error") < 0.05 * half.metric(0, "off_path_l2_error"));
  // The error on and off the visited set are the two parts of the L2 error's quadrature.
  CHECK(std::hypot(half.metric(0, "path_l2_error"), half.metric(0, "off_path_l2_error")) ==
        Approx(half.metric(0, "l2_error")).epsilon(1e-12));
}

TEST_CASE("a state-dependent plant refuses what needs a track or a linear system",
          "[adaptive][state]") {
  const auto error = [](const std::string& text) { return study_error(text, "duffing.toml"); };
  const std::string study = duffing_study("2.0", "target");
  CHECK(error(study) == "no error");
  CHECK_THAT(error(replaced(study, "laps = 300", "laps = \"limit\"")),
             Catch::Contains("duffing.toml:") && Catch::Contains("lap map") &&
                 Catch::Contains("state-dependent"));
  CHECK_THAT(error(study + "engine = \"lap_map\"\n"),
             Catch::Contains("engine = \\\"lap_map\\\"") || Catch::Contains("linear in its state"));
  CHECK_THAT(error(study + "path = { from = 0.0, to = 1.0 }\n"),
             Catch::Contains("trajectory is its own state"));
  CHECK_THAT(error(replaced(study, "name = \"rkhs\"", "name = \"rkhs_embedding\"")),
             Catch::Contains("feature coordinates") && Catch::Contains("rkhs_embedding"));
}

namespace {

// The box [0, 3.6] x [0, 4] of the read-out y = (q + 1.8, q' + 2) of a Duffing oscillator.
Domain duffing_box(bool periodic = false) {
  Domain box{3.6, periodic};
  box.dimension = 2;
  box.width = 4.0;
  return box;
}

// f(y) = -(y1 - 1.8)^3 - 0.3 (y2 - 2) + 0.2 sin(y1 y2): stiffness, damping and a coupling.
double planar_f(const double* y) {
  return -std::pow(y[0] - 1.8, 3) - 0.3 * (y[1] - 2.0) + 0.2 * std::sin(y[0] * y[1]);
}
void planar_f_gradient(const double* y, double* g) {
  g[0] = -3 * std::pow(y[0] - 1.8, 2) + 0.2 * y[1] * std::cos(y[0] * y[1]);
  g[1] = -0.3 + 0.2 * y[0] * std::cos(y[0] * y[1]);
}

}  // namespace

TEST_CASE("with a read-out of two coordinates the Jacobian and dF/dt are the rhs' derivatives",
          "[adaptive][state]") {
  const std::vector<KernelCase> kernels{{"wendland", {{"k", std::int64_t{2}}, {"radius", 1.6}}},
                                        {"gaussian", {{"sigma", 0.8}}}};
  const std::function<double(const double*)> f = planar_f;
  const std::function<void(const double*, double*)> f_gradient = planar_f_gradient;
  std::mt19937_64 random(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (const bool periodic : {false, true})
    for (const auto& kernel_case : kernels)
      for (const bool rkhs_law : {true, false}) {
        INFO(kernel_case.name << (rkhs_law ? " rkhs" : " gradient")
                              << (periodic ? " torus" : " box"));
        const Domain box = duffing_box(periodic);
        const auto plant = make_plant("duffing", {{"readout", std::string("state")},
                                                  {"offset", 1.8},
                                                  {"velocity_offset", 2.0},
                                                  {"amplitude", 1.5}});
        REQUIRE(plant->readout().rows() == 2);
        const auto kernel =
            test::make_registered_kernel(kernel_case.name, kernel_case.parameters, box);
        std::vector<double> centres;  // a 3 x 3 grid inside the box
        for (int j = 0; j < 3; ++j)
          for (int i = 0; i < 3; ++i) {
            centres.push_back(0.6 + 1.2 * i);
            centres.push_back(0.7 + 1.3 * j);
          }
        const PointSections sections(*kernel, centres);
        REQUIRE(sections.size() == 9);
        const Eigen::Index n = 9;
        const Eigen::MatrixXd P = solve_lyapunov(plant->A(), Eigen::MatrixXd::Identity(2, 2)).P;
        const Eigen::MatrixXd identity = Eigen::MatrixXd::Identity(n, n);
        const LearningMap map =
            rkhs_law
                ? LearningMap::dense(GramSolver(kernel->gram(centres), {}).solve(identity) / 0.1)
                : LearningMap::scalar(n, 10.0);
        const AdaptiveSystem system(plant->A(), plant->B(), P, sections, map, *plant, f, f_gradient,
                                    box);
        CHECK(system.readout_dimension() == 2);
        const Eigen::Index m = system.dimension();
        REQUIRE(m == 4 + n);
        for (int sample = 0; sample < 5; ++sample) {
          Eigen::VectorXd z(m);
          for (Eigen::Index i = 0; i < m; ++i) z(i) = unit(random);
          const double t = 3.0 + unit(random);
          // The read-out is C x + y0, inside the box for these states.
          double y[2];
          system.readout_point(z.data(), y);
          CHECK(y[0] == Approx(z(0) + 1.8).epsilon(1e-15));
          CHECK(y[1] == Approx(z(1) + 2.0).epsilon(1e-15));
          const auto check = check_derivatives(system, z, t, 1e-6);
          const auto& J = check.J;
          const double scale = std::max(1.0, J.cwiseAbs().maxCoeff());
          CHECK(check.jacobian_gap <= 1e-6 * scale);
          // Both read-out coordinates reach alpha' and xhat': the difference sees them.
          CHECK(J.block(4, 0, n, 1).cwiseAbs().maxCoeff() > 0);
          CHECK(J.block(4, 1, n, 1).cwiseAbs().maxCoeff() > 0);
          // x' = A x + h + B f(y): its Jacobian holds grad f(y)^T C in the velocity row.
          double g[2];
          planar_f_gradient(y, g);
          CHECK(J(1, 0) == Approx(-1.0 + g[0]).epsilon(1e-14));
          CHECK(J(1, 1) == Approx(-0.5 + g[1]).epsilon(1e-14));
          CHECK(check.time_gap <= 1e-6 * scale);
        }
        Eigen::MatrixXd J(m, m);
        CHECK_THROWS_AS(system.jacobian_matrix(0.0, J.data()), std::logic_error);
      }
  // A read-out whose size is not the domain's dimension is refused.
  const Domain box = duffing_box();
  const auto kernel = test::make_registered_kernel("gaussian", {{"sigma", 0.8}}, box);
  const std::vector<double> centres{1.0, 1.0, 2.0, 2.0};
  const PointSections sections(*kernel, centres);
  const auto position_only = make_plant("duffing", {{"offset", 1.8}});
  const Eigen::MatrixXd P = solve_lyapunov(position_only->A(), Eigen::MatrixXd::Identity(2, 2)).P;
  CHECK_THROWS_WITH(AdaptiveSystem(position_only->A(), position_only->B(), P, sections,
                                   LearningMap::scalar(2, 1.0), *position_only, f, f_gradient, box),
                    Catch::Contains("read-out C is 1 x 2") && Catch::Contains("needs 2 x 2"));
}

TEST_CASE("the visited set in d > 1 is the neighbourhood of the read-outs' polyline",
          "[adaptive][state]") {
  Domain square{1.0, false};
  square.dimension = 2;
  square.width = 1.0;
  // A path from (0.2, 0.5) to (0.8, 0.5) and on to (0.8, 0.9); reach 0.1.
  const std::vector<double> path{0.2, 0.5, 0.8, 0.5, 0.8, 0.9};
  const std::vector<double> points{
      0.5,  0.59,  // 0.09 above the first segment: inside
      0.5,  0.61,  // 0.11 above it: outside
      0.13, 0.5,   // 0.07 before its start: inside (the end's disc)
      0.09, 0.5,   // 0.11 before it: outside
      0.89, 0.7,   // 0.09 right of the second segment: inside
      0.87, 0.97,  // sqrt(0.07^2 + 0.07^2) = 0.099 from its end: inside
      0.88, 0.98,  // sqrt(2) 0.08 = 0.113 from it: outside
      0.65, 0.75,  // 0.25 from the first segment, 0.15 from the second: outside
  };
  const std::vector<bool> expected{true, false, true, false, true, true, false, false};
  CHECK(visited_neighbourhood(square, path, points, 0.1) == expected);
  // One read-out point: a disc.
  const std::vector<double> one{0.5, 0.5};
  CHECK(visited_neighbourhood(square, one, std::vector<double>{0.55, 0.58, 0.57, 0.58}, 0.1) ==
        std::vector<bool>{true, false});
  // None: nothing visited.
  CHECK(visited_neighbourhood(square, {}, points, 0.1) == std::vector<bool>(8, false));
  // On a torus distances go across the seam: (0.97, 0.5) -> (0.03, 0.5) is a segment of 0.06.
  Domain torus = square;
  torus.periodic = true;
  // In the square the same two points span its width.
  const std::vector<double> across{0.97, 0.5, 0.03, 0.5}, near{0.0, 0.55, 0.5, 0.55};
  CHECK(visited_neighbourhood(torus, across, near, 0.1) == std::vector<bool>{true, false});
  CHECK(visited_neighbourhood(square, across, near, 0.1) == std::vector<bool>{true, true});
}

namespace {

// A Duffing oscillator learning f(q + 2, q' + 2) = 0.5 sin(y1) cos(y2) on [0, 4] x [0, 4] with
// 49 Wendland sections (k = 1, radius 0.8: supports of 1.7 spacings) and the rkhs law over 200
// forcing periods of amplitude 1: its orbit, a closed curve of semi-axes about 1.3 and 1.6, stays
// in the box.
std::string planar_duffing_study(const std::string& road, const std::string& extra = "") {
  return R"toml([study]
name = "duffing_planar_test"
kind = "adaptive"
evaluation_points = 1024
metrics = ["lyapunov_max_increase", "pe_level", "unexcited_dimension", "path_l2_error",
           "off_path_l2_error", "l2_error", "final_state_error", "max_state_error"]
[domain]
lengths = [4.0, 4.0]
periodic = false
[grid]
n = [49]
[[kernel]]
name = "wendland"
k = 1
radius = 0.8
[[target]]
name = "expression"
f = "0.5 * sin(x1) * cos(x2)"
[[plant]]
name = "duffing"
readout = "state"
offset = 2.0
velocity_offset = 2.0
amplitude = 1.0
[[law]]
name = "rkhs"
gamma = 1e-2
[[integrator]]
name = "dopri5"
rtol = 1e-9
atol = 1e-11
[adaptive]
laps = 200
samples_per_lap = 100
road = ")toml" +
         road + "\"\n" + extra;
}

}  // namespace

TEST_CASE("f of a two-coordinate read-out is learnt near the orbit, and V never grows",
          "[adaptive][state]") {
  const auto outcome = test::run_study_text(planar_duffing_study("projection"));
  REQUIRE(outcome.results[0].ok);
  const auto& flags = outcome.results[0].flags;
  CHECK(std::count(flags.begin(), flags.end(), "readout_left_domain") == 0);
  // The Lyapunov argument holds for any trajectory: V' = -e^T Q e / 2 <= 0 with f in H_n, and
  // e -> 0 (measured: 5e-5 of its largest value after 200 periods).
  CHECK(outcome.metric(0, "lyapunov_max_increase") < 1e-9);
  CHECK(outcome.metric(0, "final_state_error") < 0.01 * outcome.metric(0, "max_state_error"));
  // The orbit is a curve in the box: the sections whose supports it never crosses are never
  // excited (exactly: Wendland sections vanish there), the others are; flagged.
  const auto unexcited = outcome.metric(0, "unexcited_dimension");
  CHECK(unexcited > 0);
  CHECK(unexcited < 49);
  CHECK(outcome.metric(0, "pe_level") == 0);
  CHECK(std::count(flags.begin(), flags.end(), "not_persistently_excited") == 1);
  // Learnt near the orbit, not away from it (measured: 0.098 against 0.386); the two parts
  // make up the L2 error.
  CHECK(outcome.metric(0, "path_l2_error") < 0.5 * outcome.metric(0, "off_path_l2_error"));
  CHECK(std::hypot(outcome.metric(0, "path_l2_error"), outcome.metric(0, "off_path_l2_error")) ==
        Approx(outcome.metric(0, "l2_error")).epsilon(1e-12));
}

TEST_CASE("a domain of d > 1 needs a plant that reads out d coordinates", "[adaptive][state]") {
  const auto error = [](const std::string& text) { return study_error(text, "planar.toml"); };
  const std::string study = planar_duffing_study("target");
  CHECK(error(study) == "no error");
  CHECK_THAT(error(replaced(study, "readout = \"state\"\n", "")),
             Catch::Contains("planar.toml:") && Catch::Contains("has 1 coordinate, and f") &&
                 Catch::Contains("d = 2"));
  const auto plant = study.find("[[plant]]"), law = study.find("[[law]]");
  CHECK_THAT(
      error(std::string(study).replace(plant, law - plant, "[[plant]]\nname = \"quarter_car\"\n")),
      Catch::Contains("along a track (d = 1)") && Catch::Contains("domain has d = 2"));
  CHECK_THAT(error(study + "snapshot_laps = [10]\n"),
             Catch::Contains("snapshot_laps") && Catch::Contains("d = 1"));
}

TEST_CASE("vehicle_surface: the wheel follows its path and the quarter car feels f under it",
          "[adaptive][state]") {
  // Two passes at v = 0.25 and 0.75 along u in [0, 1] at 0.5 m/s: the raster (0, 0.25) ->
  // (1, 0.25) -> (1, 0.75) -> (0, 0.75) -> back to (0, 0.25), 3 m, one lap in 6 s.
  const auto plant =
      make_plant("vehicle_surface", {{"passes", std::string("0.25; 0.75")}, {"speed", 0.5}});
  REQUIRE(plant->state_dependent());
  CHECK(plant->readout().rows() == 2);
  CHECK(plant->period() == Approx(6.0).epsilon(1e-15));
  CHECK(plant->initial_state().tail(2) == Eigen::Vector2d(0.0, 0.25));
  Domain square{1.0, false};
  square.dimension = 2;
  square.width = 1.0;
  // f(u, v) = 0.01 sin(2 pi u) (1 + v): the elevation under the wheel.
  const auto surface = [](const double* y) {
    return 0.01 * std::sin(2 * std::numbers::pi * y[0]) * (1 + y[1]);
  };
  const std::function<double(const double*)> f = surface;
  const std::function<void(const double*, double*)> f_gradient = [](const double* y, double* g) {
    g[0] = 0.02 * std::numbers::pi * std::cos(2 * std::numbers::pi * y[0]) * (1 + y[1]);
    g[1] = 0.01 * std::sin(2 * std::numbers::pi * y[0]);
  };
  const auto kernel =
      test::make_registered_kernel("wendland", {{"k", std::int64_t{1}}, {"radius", 0.6}}, square);
  std::vector<double> centres;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      centres.push_back(0.5 * i);
      centres.push_back(0.5 * j);
    }
  const PointSections sections(*kernel, centres);
  const Eigen::MatrixXd P = solve_lyapunov(plant->A(), Eigen::MatrixXd::Identity(6, 6)).P;
  // The learning sees the quarter car alone: b = P B has no part in the wheel's position.
  CHECK((P * plant->B()).tail(2).norm() == 0);
  AdaptiveSystem system(plant->A(), plant->B(), P, sections, LearningMap::scalar(9, 10.0), *plant,
                        f, f_gradient, square);
  const Eigen::Index m = system.dimension();
  REQUIRE(m == 12 + 9);

  SECTION("the Jacobian and dF/dt are the rhs' derivatives") {
    std::mt19937_64 random(5);
    std::uniform_real_distribution<double> unit(0.1, 0.9);
    for (int sample = 0; sample < 4; ++sample) {
      Eigen::VectorXd z(m);
      for (Eigen::Index i = 0; i < m; ++i) z(i) = unit(random) - 0.5;
      z.segment(4, 2) << unit(random), unit(random);  // the wheel inside the square
      z.segment(10, 2) = z.segment(4, 2);
      const double t = 0.2 + 1.3 * sample;  // inside a segment, away from its corners
      const auto check = check_derivatives(system, z, t, 1e-7);
      const double scale = check.J.cwiseAbs().maxCoeff();  // k1 / m1 = 1e5
      CHECK(check.jacobian_gap <= 1e-8 * scale);
      // alpha' sees the wheel's position.
      CHECK(check.J.block(12, 4, 9, 2).cwiseAbs().maxCoeff() > 0);
      CHECK(check.time_gap <= 1e-8 * scale);
    }
  }

  SECTION("integrated, p(t) is the path and the car is driven by f(w(t))") {
    // Independent: the quarter car [x1', x1, x2', x2] of the paper's Section 5 driven by
    // f(w(t)), w written out for this raster, by classical RK4 at h = 2e-5.
    const double m1 = 0.5, m2 = 0.5, k1 = 5e4, k2 = 3e4, c2 = 200;
    auto path = [](double t, double* w) {
      const double u = std::fmod(0.5 * t, 3.0);
      if (u < 1)
        w[0] = u, w[1] = 0.25;
      else if (u < 1.5)
        w[0] = 1, w[1] = 0.25 + (u - 1);
      else if (u < 2.5)
        w[0] = 1 - (u - 1.5), w[1] = 0.75;
      else
        w[0] = 0, w[1] = 0.75 - (u - 2.5);
    };
    auto car = [&](double t, const Eigen::Vector4d& x) {
      double w[2];
      path(t, w);
      const double road = surface(w);
      Eigen::Vector4d dx;
      dx(0) = (-k1 * (x(1) - road) - k2 * (x(1) - x(3)) - c2 * (x(0) - x(2))) / m1;
      dx(1) = x(0);
      dx(2) = (k2 * (x(1) - x(3)) + c2 * (x(0) - x(2))) / m2;
      dx(3) = x(2);
      return dx;
    };
    const double final_time = 7.0;  // a lap and a sixth: across every corner and the seam
    Eigen::Vector4d x = Eigen::Vector4d::Zero();
    const double h = 2e-5;
    const int steps = static_cast<int>(final_time / h + 0.5);
    for (int k = 0; k < steps; ++k) {
      const double t = k * h;
      const Eigen::Vector4d k1v = car(t, x), k2v = car(t + h / 2, x + h / 2 * k1v),
                            k3v = car(t + h / 2, x + h / 2 * k2v), k4v = car(t + h, x + h * k3v);
      x += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
    }
    double w_end[2];
    path(final_time, w_end);
    for (const std::string integrator_name : {"radau5", "dopri5"}) {
      INFO(integrator_name);
      const auto integrator = make_integrator(integrator_name, {{"rtol", 1e-10}, {"atol", 1e-13}});
      Eigen::VectorXd z = Eigen::VectorXd::Zero(m);
      z.head(6) = plant->initial_state();
      z.segment(6, 6) = plant->initial_state();
      // Land on every corner of the path: w' jumps there.
      const std::vector<double> times{0.0, 2.0, 3.0, 5.0, 6.0, final_time};
      integrator->integrate(system, z, times, [](std::size_t, const double*) {});
      CHECK(z(4) == Approx(w_end[0]).margin(1e-9));
      CHECK(z(5) == Approx(w_end[1]).margin(1e-9));
      // The car's suspension travel x1 - x2 and x1 (millimetres here) against the reference.
      CHECK(z(1) == Approx(x(1)).margin(1e-8));
      CHECK(z(3) == Approx(x(3)).margin(1e-8));
      CHECK(z(0) == Approx(x(0)).margin(1e-6));
    }
  }
}

TEST_CASE("vehicle_surface refuses a path it cannot drive", "[adaptive][state]") {
  const auto* entry = plant_registry().find("vehicle_surface");
  REQUIRE(entry);
  auto make = [&](std::map<std::string, ParameterValue> given) {
    try {
      entry->factory(ParameterSet::resolve(entry->info.parameters, given));
    } catch (const ParameterError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK(make({{"passes", std::string("0.5")}}) == "no error");
  CHECK_THAT(make({}), Catch::Contains("exactly one of waypoints"));
  CHECK_THAT(make({{"passes", std::string("0.5")}, {"waypoints", std::string("0 0; 1 1")}}),
             Catch::Contains("exactly one of waypoints"));
  CHECK_THAT(make({{"waypoints", std::string("0 0 1; 1 1 1")}}),
             Catch::Contains("2 coordinates 'u v'"));
  CHECK_THAT(make({{"waypoints", std::string("0 0; 0 0")}}), Catch::Contains("coincide"));
  CHECK_THAT(make({{"passes", std::string("0.2 0.4")}}), Catch::Contains("separated by ';'"));
}
