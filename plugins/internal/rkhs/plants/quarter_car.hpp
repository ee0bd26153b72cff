#pragma once
// The quarter car of the paper's Section 5, shared by the plants that drive it: quarter_car
// (f along a track) and vehicle_surface (f a surface under a path in the plane).
#include <Eigen/Dense>
#include <vector>

#include "rkhs/core/parameters.hpp"

namespace rkhs::quarter_car {

/// m1, m2, k1, k2, c2 and paper_sign, with the paper's values as defaults.
std::vector<ParameterSpec> parameters();

/// A (4 x 4) and B (4) of the state [x1', x1, x2', x2] for the parameters of parameters():
///   m1 x1'' = -k1 (x1 - f) - k2 (x1 - x2) - c2 (x1' - x2'),
///   m2 x2'' =  k2 (x1 - x2) + c2 (x1' - x2')   (-c2 with paper_sign: the paper's printed sign),
/// f the road's elevation under the wheel. Throws std::invalid_argument unless A is Hurwitz.
void system(const ParameterSet& p, Eigen::MatrixXd& A, Eigen::VectorXd& B);

}  // namespace rkhs::quarter_car
