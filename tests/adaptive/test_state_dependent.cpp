// State-dependent plants (docs/model.md section 18): f of the read-out y = c^T x + y0.
//   - the exact Jacobian and dF/dt of the coupled system against differences of its rhs;
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
  struct KernelCase {
    std::string name;
    std::map<std::string, ParameterValue> parameters;
  };
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
          Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> J(m, m);
          Eigen::VectorXd dfdt(m);
          system.jacobian(z.data(), J.data(), t, dfdt.data());
          // Central differences, step 1e-6: truncation ~1e-12 |F'''|, round-off ~1e-10 |F|.
          const double step = 1e-6;
          Eigen::VectorXd up(m), down(m), z_up, z_down;
          Eigen::MatrixXd difference(m, m);
          for (Eigen::Index j = 0; j < m; ++j) {
            z_up = z;
            z_down = z;
            z_up(j) += step;
            z_down(j) -= step;
            system.rhs(z_up.data(), up.data(), t);
            system.rhs(z_down.data(), down.data(), t);
            difference.col(j) = (up - down) / (2 * step);
          }
          const double scale = std::max(1.0, J.cwiseAbs().maxCoeff());
          CHECK((Eigen::MatrixXd(J) - difference).cwiseAbs().maxCoeff() <= 1e-6 * scale);
          // The read-out couples x to alpha': the difference sees it, so the check is not empty.
          CHECK(J.block(2 * 2, 0, m - 4, 1).cwiseAbs().maxCoeff() > 0);
          system.rhs(z.data(), up.data(), t + step);
          system.rhs(z.data(), down.data(), t - step);
          CHECK(((up - down) / (2 * step) - dfdt).cwiseAbs().maxCoeff() <= 1e-6 * scale);
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
  const auto error = [](const std::string& text) {
    try {
      parse_study(text, "duffing.toml");
    } catch (const StudyError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  auto with = [](std::string text, const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    REQUIRE(at != std::string::npos);
    return text.replace(at, from.size(), to);
  };
  const std::string study = duffing_study("2.0", "target");
  CHECK(error(study) == "no error");
  CHECK_THAT(error(with(study, "laps = 300", "laps = \"limit\"")),
             Catch::Contains("duffing.toml:") && Catch::Contains("lap map") &&
                 Catch::Contains("state-dependent"));
  CHECK_THAT(error(study + "engine = \"lap_map\"\n"),
             Catch::Contains("engine = \\\"lap_map\\\"") || Catch::Contains("linear in its state"));
  CHECK_THAT(error(study + "path = { from = 0.0, to = 1.0 }\n"),
             Catch::Contains("trajectory is its own state"));
  CHECK_THAT(error(with(study, "name = \"rkhs\"", "name = \"rkhs_embedding\"")),
             Catch::Contains("feature coordinates") && Catch::Contains("rkhs_embedding"));
}
