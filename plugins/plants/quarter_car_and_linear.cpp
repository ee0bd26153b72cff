// Built-in plants: quarter_car (the paper's Section 5) and linear (A and B from the study file).
#include <fmt/format.h>

#include <stdexcept>

#include "rkhs/adaptive/lyapunov.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/plants/quarter_car.hpp"

namespace rkhs {

std::vector<ParameterSpec> quarter_car::parameters() {
  return {positive_parameter("m1", 0.5, "unsprung mass, kg"),
          positive_parameter("m2", 0.5, "sprung mass, kg"),
          positive_parameter("k1", 5e4, "tyre stiffness, N/m"),
          positive_parameter("k2", 3e4, "suspension stiffness, N/m"),
          positive_parameter("c2", 200.0, "suspension damping, N s/m"),
          boolean_parameter("paper_sign", false,
                            "use the paper's printed -c2/m2 in A[2][0] (Newton gives +c2/m2)")};
}

void quarter_car::system(const ParameterSet& p, Eigen::MatrixXd& A, Eigen::VectorXd& B) {
  const double m1 = p.real("m1"), m2 = p.real("m2"), k1 = p.real("k1"), k2 = p.real("k2"),
               c2 = p.real("c2");
  const double a20 = (p.boolean("paper_sign") ? -1.0 : 1.0) * c2 / m2;
  A.resize(4, 4);
  B.resize(4);
  A << -c2 / m1, -(k1 + k2) / m1, c2 / m1, k2 / m1,  //
      1, 0, 0, 0,                                    //
      a20, k2 / m2, -c2 / m2, -k2 / m2,              //
      0, 0, 1, 0;
  B << k1 / m1, 0, 0, 0;
  require_hurwitz(A);
}

namespace {

/// The quarter car of the paper's Section 5, state x = [x1', x1, x2', x2].
class QuarterCar final : public Plant {
 public:
  static PluginInfo info() {
    return {"quarter_car",
            "quarter-car suspension of the paper's Section 5, state [x1', x1, x2', x2]",
            quarter_car::parameters(),
            {{"dimension", "4"}}};
  }
  explicit QuarterCar(const ParameterSet& p) { quarter_car::system(p, A_, B_); }
  const Eigen::MatrixXd& A() const noexcept override { return A_; }
  const Eigen::VectorXd& B() const noexcept override { return B_; }

 private:
  Eigen::MatrixXd A_;
  Eigen::VectorXd B_;
};

/// x' = A x + B f with A and B written in the study file.
class LinearPlant final : public Plant {
 public:
  static PluginInfo info() {
    return {"linear",
            "x' = A x + B f with A (Hurwitz) and B given, e.g. A = \"-1 0; 0 -2\", B = \"1; 0\"",
            {text_parameter("A", "-1", "the d x d matrix A: rows separated by ';'"),
             text_parameter("B", "1", "the d x 1 matrix B: entries separated by ';'")},
            {}};
  }
  explicit LinearPlant(const ParameterSet& p) {
    A_ = parse_matrix(p.text("A"));
    const Eigen::MatrixXd b = parse_matrix(p.text("B"));
    if (A_.rows() != A_.cols())
      throw ParameterError("A",
                           fmt::format("A must be square, found {} x {}", A_.rows(), A_.cols()));
    if (b.cols() != 1 || b.rows() != A_.rows())
      throw ParameterError("B", fmt::format("B must be {} x 1 (one entry per row, separated by "
                                            "';'), found {} x {}",
                                            A_.rows(), b.rows(), b.cols()));
    B_ = b.col(0);
    require_hurwitz(A_);
  }
  const Eigen::MatrixXd& A() const noexcept override { return A_; }
  const Eigen::VectorXd& B() const noexcept override { return B_; }

 private:
  Eigen::MatrixXd A_;
  Eigen::VectorXd B_;
};

}  // namespace
}  // namespace rkhs

RKHS_REGISTER_PLANT(rkhs::QuarterCar)
RKHS_REGISTER_PLANT(rkhs::LinearPlant)
