// solve_lyapunov (rkhs/adaptive/lyapunov.hpp): A^T P + P A + Q = 0 solved to round-off, with a
// closed form and the refusals (A not Hurwitz, Q not positive definite).
#include <catch2/catch.hpp>

#include "rkhs/adaptive/lyapunov.hpp"
#include "rkhs/adaptive/plant.hpp"

using namespace rkhs;

namespace {

std::unique_ptr<Plant> quarter_car() {
  const auto* entry = plant_registry().find("quarter_car");
  return entry->factory(ParameterSet::resolve(entry->info.parameters, {}));
}

}  // namespace

TEST_CASE("Lyapunov solver: residual, symmetry, definiteness", "[adaptive]") {
  const auto plant = quarter_car();
  for (const std::string q : {"identity", "diag(1e-4, 1, 1e-4, 1)"}) {
    const Eigen::MatrixXd Q = parse_matrix(q, 4);
    const auto solution = solve_lyapunov(plant->A(), Q);
    const Eigen::MatrixXd& P = solution.P;
    INFO("Q = " << q);
    CHECK((P - P.transpose()).norm() == 0.0);
    CHECK(solution.min_eigenvalue > 0);
    // Backward error at the level of round-off (A has entries of 1.6e5, so the residual
    // relative to Q alone is about 1e-9 and says nothing).
    const double backward = (plant->A().transpose() * P + P * plant->A() + Q).norm() /
                            (2 * plant->A().norm() * P.norm() + Q.norm());
    CHECK(backward < 1e-14);
    CHECK(solution.relative_residual == Approx(backward));
  }
  // A 2 x 2 closed form: A = diag(-1, -2), Q = I gives P = diag(1/2, 1/4).
  const auto diagonal = solve_lyapunov(parse_matrix("-1 0; 0 -2"), Eigen::MatrixXd::Identity(2, 2));
  CHECK(diagonal.P(0, 0) == Approx(0.5).epsilon(1e-14));
  CHECK(diagonal.P(1, 1) == Approx(0.25).epsilon(1e-14));
  CHECK(std::abs(diagonal.P(0, 1)) < 1e-15);
  CHECK_THROWS_WITH(solve_lyapunov(parse_matrix("1 0; 0 -2"), Eigen::MatrixXd::Identity(2, 2)),
                    Catch::StartsWith("A is not Hurwitz: eigenvalue 1+0i"));
  CHECK_THROWS_WITH(solve_lyapunov(parse_matrix("-1 0; 0 -2"), parse_matrix("1 2; 2 1")),
                    "Q must be positive definite");
}
