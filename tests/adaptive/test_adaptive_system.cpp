// The coupled plant / estimator / learning-law system: exact Jacobian and dF/dt.
#include <catch2/catch.hpp>
#include <numbers>
#include <set>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/adaptive/lyapunov.hpp"
#include "rkhs/adaptive/plant.hpp"

using namespace rkhs;

namespace {

std::unique_ptr<AnyKernel> kernel(const std::string& name, std::map<std::string, ParameterValue> p,
                                  const Domain& domain) {
  const auto* entry = kernel_registry().find(name);
  REQUIRE(entry);
  return entry->factory(ParameterSet::resolve(entry->info.parameters, p), domain);
}

std::unique_ptr<Plant> quarter_car() {
  const auto* entry = plant_registry().find("quarter_car");
  return entry->factory(ParameterSet::resolve(entry->info.parameters, {}));
}

}  // namespace

TEST_CASE("the Jacobian and dF/dt of the coupled system match finite differences", "[adaptive]") {
  const Domain track{2 * std::numbers::pi * 4, true};
  const auto plant = quarter_car();
  const auto P = solve_lyapunov(plant->A(), Eigen::MatrixXd::Identity(4, 4)).P;
  for (const std::string name : {"gaussian", "bspline"}) {
    const auto k = kernel(name, {}, track);
    std::vector<double> centres;
    for (int i = 0; i < 7; ++i) centres.push_back(track.length * i / 7.0);
    const auto basis = k->basis(centres);
    const Eigen::MatrixXd map = Eigen::MatrixXd::Identity(7, 7) * 3.0;
    const double wave = 2 * std::numbers::pi / track.length;
    const std::function<double(double)> road = [&](double s) { return 2 * std::sin(wave * s); };
    const std::function<double(double)> slope = [&](double s) {
      return 2 * wave * std::cos(wave * s);
    };
    AdaptiveSystem system(plant->A(), plant->B(), P, *basis, map, road, slope, track, 0.7);
    const auto m = system.dimension();
    REQUIRE(m == 15);
    Eigen::VectorXd z(m);
    for (Eigen::Index i = 0; i < m; ++i) z(i) = std::sin(1.0 + static_cast<double>(i));
    const double t = 3.3;  // s = 2.31: not a knot of the B-spline kernel
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> J(m, m);
    Eigen::VectorXd dfdt(m), f0(m), fp(m), fm(m);
    system.jacobian(z.data(), J.data(), t, dfdt.data());
    system.rhs(z.data(), f0.data(), t);
    // The system is linear in z: a difference quotient is exact up to round-off.
    for (Eigen::Index j = 0; j < m; ++j) {
      Eigen::VectorXd zp = z, zm = z;
      const double h = 1e-3;
      zp(j) += h;
      zm(j) -= h;
      system.rhs(zp.data(), fp.data(), t);
      system.rhs(zm.data(), fm.data(), t);
      const Eigen::VectorXd column = (fp - fm) / (2 * h);
      INFO(name << " column " << j);
      CHECK((column - J.col(j)).norm() <= 1e-8 * (1 + J.col(j).norm()));
    }
    // dF/dt (exact) against a Richardson-extrapolated central difference in t, O(h^4).
    auto central = [&](double h) {
      system.rhs(z.data(), fp.data(), t + h);
      system.rhs(z.data(), fm.data(), t - h);
      return Eigen::VectorXd((fp - fm) / (2 * h));
    };
    const Eigen::VectorXd extrapolated = (4 * central(5e-3) - central(1e-2)) / 3;
    CHECK((extrapolated - dfdt).norm() <= 1e-7 * (1 + dfdt.norm()));
    CHECK(dfdt.norm() > 0);
  }
}

TEST_CASE("the adaptive metric table: rows in enum order, each named once", "[adaptive]") {
  // The output order and every row's facts are docs/metrics.md's catalogue, which
  // docs.metrics_catalogue checks against `rkhs-study list metrics`; here the table's own rules.
  STATIC_REQUIRE(table_in_enum_order<AdaptiveMetric>());
  CHECK(adaptive_metric_names() == metric_table_names<AdaptiveMetric>());
  const auto names = metric_table_names<AdaptiveMetric>();
  CHECK(std::set<std::string>(names.begin(), names.end()).size() == names.size());
  for (const auto& row : MetricTable<AdaptiveMetric>::rows) {
    INFO(row.name);
    if (row.flag.ends_with("_at_floor")) CHECK(row.floor != FloorRule::exact);
    // An adaptive trial computes every metric; Theorem 1's need the initial data dependence.
    CHECK((row.needs & ~unsigned{adaptive_work_initial_data}) == 0);
  }
}
