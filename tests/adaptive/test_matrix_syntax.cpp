// parse_matrix (rkhs/adaptive/plant.hpp): the matrix syntax of study files (rows separated by
// ';', diag(...), identity) and its error messages.
#include <catch2/catch.hpp>

#include "rkhs/adaptive/plant.hpp"
#include "rkhs/adaptive/weight_matrix.hpp"

using namespace rkhs;

TEST_CASE("matrix syntax of study files", "[adaptive]") {
  CHECK(parse_matrix("-1 0; 0 -2") == (Eigen::MatrixXd(2, 2) << -1, 0, 0, -2).finished());
  CHECK(parse_matrix("1; 0") == (Eigen::MatrixXd(2, 1) << 1, 0).finished());
  CHECK(parse_matrix("diag(1, 2)") == (Eigen::MatrixXd(2, 2) << 1, 0, 0, 2).finished());
  CHECK(parse_matrix("identity", 3) == Eigen::MatrixXd::Identity(3, 3));
  CHECK_THROWS_WITH(parse_matrix("1 2; 3"),
                    "in matrix \"1 2; 3\": row 2 has 1 entries, row 1 has 2");
  CHECK_THROWS_WITH(parse_matrix("1 x"), "in matrix \"1 x\": 'x' is not a number");
}

TEST_CASE("a weight matrix is parsed once and resolved for a dimension", "[adaptive]") {
  CHECK(WeightMatrix().for_dimension(3) == Eigen::MatrixXd::Identity(3, 3));
  CHECK(WeightMatrix::parse(" I ").for_dimension(2) == Eigen::MatrixXd::Identity(2, 2));
  const auto q = WeightMatrix::parse("diag(1, 2)");
  CHECK(q.text() == "diag(1, 2)");
  CHECK(q.for_dimension(2) == (Eigen::MatrixXd(2, 2) << 1, 0, 0, 2).finished());
  CHECK_THROWS_WITH(q.for_dimension(4, "adaptive.q"),
                    "adaptive.q is 2 x 2, this plant needs 4 x 4");
  CHECK_THROWS_WITH(WeightMatrix::parse("1 x"), "in matrix \"1 x\": 'x' is not a number");
}
