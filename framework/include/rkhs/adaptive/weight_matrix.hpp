#pragma once
// Weight matrices of study files, parsed once (defined with the matrix syntax, plant.cpp).

#include <Eigen/Dense>
#include <string>
#include <string_view>

namespace rkhs {

/// A square weight matrix of a study file (adaptive.q, the Q of the Lyapunov equation), parsed
/// once: "identity" (of any size), or a given matrix in parse_matrix's syntax. Keeps the text
/// it was read from (which enters the trial identity as written).
class WeightMatrix {
 public:
  WeightMatrix() = default;  ///< the identity
  /// Throws std::invalid_argument saying what is wrong with `text` (parse_matrix).
  static WeightMatrix parse(std::string_view text);
  const std::string& text() const noexcept { return text_; }
  /// The matrix for a system of `d` states: I_d, or the given matrix, which must be d x d
  /// (std::invalid_argument otherwise: "<name> is r x c, this plant needs d x d").
  Eigen::MatrixXd for_dimension(Eigen::Index d, std::string_view name = "Q") const;
  bool operator==(const WeightMatrix& other) const { return text_ == other.text_; }

 private:
  std::string text_ = "identity";
  Eigen::MatrixXd given_;  ///< empty for the identity
};

}  // namespace rkhs
