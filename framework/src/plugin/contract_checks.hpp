#pragma once
// Internal to the plugin layer: what the kernel contract's checks share (kernel_contract.cpp,
// kernel_contract_derivatives.cpp): the report's check list, number formatting, the Gram
// spectrum's round-off rule, and the derivative and gradient checks.

#include <fmt/format.h>

#include <Eigen/Dense>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "rkhs/plugin/kernel_contract.hpp"

namespace rkhs::contract_detail {

inline constexpr double epsilon = std::numeric_limits<double>::epsilon();

inline std::string g(double value) {
  return fmt::format("{:.3g}", value);
}

class Checks {
 public:
  explicit Checks(ContractReport& report) : report_(report) {}
  void add(std::string name, bool passed, std::string detail) {
    report_.checks.push_back({std::move(name), passed, false, std::move(detail)});
  }
  void skip(std::string name, std::string why) {
    report_.checks.push_back({std::move(name), true, true, std::move(why)});
  }
  /// "measured <= tolerance" checks.
  void at_most(std::string name, std::string what, double measured, double tolerance) {
    add(std::move(name), measured <= tolerance,
        fmt::format("{} = {} (tolerance {})", what, g(measured), g(tolerance)));
  }

 private:
  ContractReport& report_;
};

// Smallest eigenvalue of G relative to round-off: PSD to working precision when
// lambda_min >= -64 n eps lambda_max (eigenvalue error of a symmetric solver ~ n eps ||G||).
struct Spectrum {
  Eigen::VectorXd lambda;
  double allowed_negative = 0;
};
inline Spectrum spectrum_of(const Eigen::MatrixXd& gram) {
  Spectrum s;
  s.lambda =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(gram, Eigen::EigenvaluesOnly).eigenvalues();
  s.allowed_negative = 64 * static_cast<double>(gram.rows()) * epsilon * s.lambda.maxCoeff();
  return s;
}

// The derivative checks (kernel_contract.hpp): derivative() against Richardson extrapolation,
// and a basis' derivatives against derivative().
void check_derivatives(const AnyKernel& kernel, double scale, Checks& checks);

// The gradient check (d > 1): each component of gradient_point(c, y) against Richardson
// extrapolation of k(c, .) along that axis, where the section is smooth along the stretch.
// `scatter(count, start)`: scattered points of the kernel's domain.
void check_gradient(const AnyKernel& kernel, double scale, Checks& checks,
                    const std::function<std::vector<double>(std::size_t, double)>& scatter);

}  // namespace rkhs::contract_detail
