// A plugin module with a plant and a learning law instead of a kernel: a damped mass on a spring
// driven by the road, and the gradient law with its gain given as a product.
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/plugin/module.hpp"

namespace {

class MassSpring final : public rkhs::Plant {
 public:
  static rkhs::PluginInfo info() {
    return {"test_mass_spring",
            "x1' = x2, x2' = -k x1 - c x2 + f: A = [0 1; -k -c], B = [0; 1]",
            {rkhs::positive_parameter("k", 4.0, "spring stiffness per unit mass"),
             rkhs::positive_parameter("c", 2.0, "damping per unit mass")},
            {}};
  }
  explicit MassSpring(const rkhs::ParameterSet& p) : A_(2, 2), B_(2) {
    A_ << 0.0, 1.0, -p.real("k"), -p.real("c");
    B_ << 0.0, 1.0;
  }
  const Eigen::MatrixXd& A() const noexcept override { return A_; }
  const Eigen::VectorXd& B() const noexcept override { return B_; }

 private:
  Eigen::MatrixXd A_;
  Eigen::VectorXd B_;
};

class ScaledGradientLaw final : public rkhs::LearningLaw {
 public:
  static rkhs::PluginInfo info() {
    return {"test_scaled_gradient",
            "the gradient law with Gamma = gamma * scale",
            {rkhs::positive_parameter("gamma", 1.0, "base gain"),
             rkhs::positive_parameter("scale", 1.0, "factor on the gain")},
            {}};
  }
  explicit ScaledGradientLaw(const rkhs::ParameterSet& p)
      : gain_(p.real("gamma") * p.real("scale")) {}
  bool uses_gram_inverse() const noexcept override { return false; }
  double gain() const noexcept override { return gain_; }

 private:
  double gain_;
};

}  // namespace

RKHS_REGISTER_PLANT(MassSpring)
RKHS_REGISTER_LAW(ScaledGradientLaw)
RKHS_PLUGIN_MODULE("adaptive_parts")
