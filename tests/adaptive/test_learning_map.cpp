// The learning map M in psi = M phi: its three forms apply the same M, the rkhs law's G^+ is
// kept in low rank exactly when that is cheaper, and the coupled system is the same with M in
// any form.
#include <catch2/catch.hpp>
#include <numbers>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/adaptive/learning_map.hpp"
#include "rkhs/adaptive/lyapunov.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/approx/gram_solver.hpp"
#include "rkhs/kernel/kernel_algorithms.hpp"

using namespace rkhs;

namespace {

std::unique_ptr<AnyKernel> kernel(const std::string& name, std::map<std::string, ParameterValue> p,
                                  const Domain& domain) {
  const auto* entry = kernel_registry().find(name);
  REQUIRE(entry);
  return entry->factory(ParameterSet::resolve(entry->info.parameters, p), domain);
}

std::vector<double> uniform_centres(const Domain& domain, int n) {
  std::vector<double> centres;
  for (int i = 0; i < n; ++i) centres.push_back(domain.length * i / n);
  return centres;
}

double relative_difference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).norm() / std::max(b.norm(), 1e-300);
}

}  // namespace

TEST_CASE("the three forms of the learning map apply the same M", "[adaptive]") {
  const Eigen::Index n = 30, r = 7;
  const Eigen::MatrixXd V = Eigen::MatrixXd::Random(n, r);
  const Eigen::VectorXd w = Eigen::VectorXd::Random(r).cwiseAbs() + Eigen::VectorXd::Ones(r);
  const Eigen::MatrixXd dense = V * w.asDiagonal() * V.transpose();
  const Eigen::VectorXd phi = Eigen::VectorXd::Random(n);
  Eigen::VectorXd psi(n);

  const auto low = LearningMap::low_rank(V, w);
  CHECK(low.form() == LearningMap::Form::low_rank);
  CHECK(low.rank() == r);
  low.apply(phi.data(), psi.data());
  CHECK(relative_difference(psi, dense * phi) < 1e-14);
  CHECK((low.matrix() - dense).norm() <= 1e-14 * dense.norm());

  const auto full = LearningMap::dense(dense);
  CHECK(full.form() == LearningMap::Form::dense);
  CHECK(full.rank() == n);
  full.apply(phi.data(), psi.data());
  CHECK(psi == dense * phi);  // the same product, bit for bit

  // A multiple of the identity is a scalar, whichever way it is given, and exact.
  const auto scaled = LearningMap::dense(Eigen::MatrixXd::Identity(n, n) / 2e4);
  CHECK(scaled.form() == LearningMap::Form::scalar);
  scaled.apply(phi.data(), psi.data());
  for (Eigen::Index i = 0; i < n; ++i) CHECK(psi(i) == phi(i) * (1 / 2e4));
  CHECK(scaled.matrix() == Eigen::MatrixXd(Eigen::MatrixXd::Identity(n, n) / 2e4));

  CHECK_THROWS_AS(LearningMap::low_rank(V, Eigen::VectorXd::Ones(r + 1)), std::invalid_argument);
  CHECK_THROWS_AS(LearningMap::dense(Eigen::MatrixXd::Ones(3, 4)), std::invalid_argument);
}

TEST_CASE("the rkhs law's G^-1 / Gamma is low rank exactly where the pseudo-inverse is cheaper",
          "[adaptive]") {
  const Domain track{2 * std::numbers::pi * 4, true};
  const double gain = 2e4;
  struct Case {
    std::string name;
    std::map<std::string, ParameterValue> parameters;
    int n;
    LearningMap::Form form;
  };
  // Gaussian sigma = 1 on the 25 m track: numerical rank about 63, whatever n. Wendland: full
  // rank (Cholesky). Gaussian n = 100: rank 63 > n / 2, so the dense product is cheaper.
  for (const auto& c : {Case{"gaussian", {{"sigma", 1.0}}, 300, LearningMap::Form::low_rank},
                        Case{"gaussian", {{"sigma", 1.0}}, 100, LearningMap::Form::dense},
                        Case{"wendland", {}, 60, LearningMap::Form::dense}}) {
    INFO(c.name << " n = " << c.n);
    const auto k = kernel(c.name, c.parameters, track);
    const auto centres = uniform_centres(track, c.n);
    const GramSolver solver(k->gram(centres), {});
    const auto map = LearningMap::gram_inverse(solver, gain);
    CHECK(map.form() == c.form);
    CHECK(map.size() == c.n);
    if (c.form == LearningMap::Form::low_rank) CHECK(2 * map.rank() < c.n);
    // M phi(s) at a few points: the low-rank form is the solver's own pseudo-inverse solve
    // (the same operations), the dense form the product with G^-1 formed once, as before.
    // The two need not agree closely: a pseudo-inverse that keeps eigenvalues down to
    // n eps lambda_max is as ill-conditioned as that (at n = 100, G^+ phi formed either way
    // differs by about 2e-4 relative).
    const auto basis = k->basis(centres);
    const Eigen::MatrixXd inverse =
        solver.solve(Eigen::MatrixXd(Eigen::MatrixXd::Identity(c.n, c.n))) / gain;
    Eigen::VectorXd phi(c.n), psi(c.n);
    for (double s : {0.3, 7.1, 19.9}) {
      basis->evaluate(s, phi.data());
      map.apply(phi.data(), psi.data());
      if (c.form == LearningMap::Form::low_rank)
        CHECK(relative_difference(psi, solver.solve(phi) / gain) < 1e-12);
      else
        CHECK(psi == inverse * phi);
    }
  }
}

TEST_CASE("the coupled system is the same with the rkhs law's map low rank or dense",
          "[adaptive]") {
  const Domain track{2 * std::numbers::pi * 4, true};
  const auto* plant_entry = plant_registry().find("quarter_car");
  const auto plant = plant_entry->factory(ParameterSet::resolve(plant_entry->info.parameters, {}));
  const auto P = solve_lyapunov(plant->A(), Eigen::MatrixXd::Identity(4, 4)).P;
  const std::function<double(double)> road = [](double s) { return 2 * std::sin(s / 4); };
  const std::function<double(double)> slope = [](double s) { return 0.5 * std::cos(s / 4); };
  const int n = 300;
  const auto k = kernel("gaussian", {{"sigma", 1.0}}, track);
  const auto centres = uniform_centres(track, n);
  // G's 20 largest eigenpairs: a well-conditioned M, so that its dense and low-rank products
  // agree to round-off and any difference is the system's.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(k->gram(centres));
  const auto low = LearningMap::low_rank(eigen.eigenvectors().rightCols(20),
                                         (2e4 * eigen.eigenvalues().tail(20)).cwiseInverse());
  const auto low_basis = k->basis(centres), dense_basis = k->basis(centres);
  AdaptiveSystem low_system(plant->A(), plant->B(), P, *low_basis, low, road, slope, track, 1e-4);
  AdaptiveSystem dense_system(plant->A(), plant->B(), P, *dense_basis, low.matrix(), road, slope,
                              track, 1e-4);
  const auto m = low_system.dimension();
  const Eigen::VectorXd z = Eigen::VectorXd::Random(m);
  Eigen::VectorXd low_dz(m), dense_dz(m), low_dfdt(m), dense_dfdt(m);
  for (double t : {0.0, 1.3e4, 2.2e5}) {
    low_system.rhs(z.data(), low_dz.data(), t);
    dense_system.rhs(z.data(), dense_dz.data(), t);
    CHECK(relative_difference(low_dz, dense_dz) < 1e-12);
    low_system.time_derivative(z.data(), t, low_dfdt.data());
    dense_system.time_derivative(z.data(), t, dense_dfdt.data());
    CHECK(relative_difference(low_dfdt, dense_dfdt) < 1e-12);
  }
  // A map of the wrong size is refused.
  CHECK_THROWS_AS(AdaptiveSystem(plant->A(), plant->B(), P, *low_basis,
                                 LearningMap::scalar(n + 1, 1.0), road, slope, track, 1e-4),
                  std::invalid_argument);
}

TEST_CASE("a learning map c I is recognised exactly and applied as a scalar by every basis",
          "[adaptive]") {
  CHECK(identity_multiple(Eigen::MatrixXd::Identity(4, 4) * 0.25) == 0.25);
  Eigen::MatrixXd almost = Eigen::MatrixXd::Identity(4, 4);
  almost(1, 2) = 1e-300;
  CHECK_FALSE(identity_multiple(almost));
  almost = Eigen::MatrixXd::Identity(4, 4);
  almost(3, 3) = 1 + 1e-16 * 4;
  CHECK_FALSE(identity_multiple(almost));
  CHECK_FALSE(identity_multiple(Eigen::MatrixXd::Identity(3, 4)));
  CHECK_FALSE(identity_multiple(Eigen::MatrixXd()));

  // A feature-map basis (B-spline: c scales its features, so psi sums c-scaled columns) and a
  // direct one (Wendland: psi = c phi, bit for bit).
  const Domain track{2 * std::numbers::pi * 4, true};
  for (const std::string name : {"bspline", "wendland"}) {
    INFO(name);
    const auto k = kernel(name, {}, track);
    const auto centres = uniform_centres(track, 24);
    const auto basis = k->basis(centres);
    basis->set_map(Eigen::MatrixXd::Identity(24, 24) / 2e4);
    std::vector<double> phi(24), psi(24);
    for (double s : {0.3, 7.1, 19.9}) {
      basis->evaluate(s, phi.data());
      basis->evaluate_mapped(s, psi.data());
      for (std::size_t i = 0; i < phi.size(); ++i)
        if (name == "wendland")
          CHECK(psi[i] == (1 / 2e4) * phi[i]);
        else
          CHECK(psi[i] == Approx((1 / 2e4) * phi[i]).epsilon(1e-15));
    }
  }
}
