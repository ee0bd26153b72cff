#pragma once
// The linear systems of an implicit step of an AdaptiveSystem, (c I - J(t)) k = r for a real or
// complex shift c: solved with the structure of J (rkhs/adaptive/coupled_structure.hpp,
// O(d^3 + n) to factor and O(d^2 + n) per solve), or through the dense (2d + n)^2 matrix, the
// reference the structured solves are tested against (O((2d + n)^3) per factorisation).

#include <Eigen/Dense>
#include <complex>
#include <string_view>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/adaptive/coupled_structure.hpp"

namespace rkhs {

enum class LinearSolver { structured, dense };

/// "structured" or "dense"; throws std::invalid_argument naming the allowed values.
LinearSolver linear_solver_from_name(std::string_view name);

/// Factorisations of (c I - J(t)) for one real and, when asked, one complex shift, and solves
/// with them (each column of the right-hand side in place). The system must outlive it.
class StageSolves {
 public:
  /// A state-dependent system (AdaptiveSystem::state_dependent) has no structured form: its
  /// solves are dense whatever `kind` asks.
  StageSolves(const AdaptiveSystem& system, LinearSolver kind);

  /// J = J(t, z); factorises (real_shift I - J). Throws SingularStageMatrix when singular. z
  /// (dimension() doubles) is read by a state-dependent system only, and may be null for the
  /// others.
  void factor(double t, const double* z, double real_shift);
  /// J = J(t, z); factorises (real_shift I - J) and (complex_shift I - J).
  void factor(double t, const double* z, double real_shift, std::complex<double> complex_shift);
  /// The same for a system linear in z (J = J(t)).
  void factor(double t, double real_shift) { factor(t, nullptr, real_shift); }
  void factor(double t, double real_shift, std::complex<double> complex_shift) {
    factor(t, nullptr, real_shift, complex_shift);
  }

  void solve_real(Eigen::Ref<Eigen::MatrixXd> rhs) const;
  void solve_complex(Eigen::Ref<Eigen::MatrixXcd> rhs) const;

 private:
  void linearize(double t, const double* z);
  const AdaptiveSystem& system_;
  LinearSolver kind_;
  // structured
  CoupledLinearization linearization_;
  ShiftedCoupledSolver<double> real_;
  ShiftedCoupledSolver<std::complex<double>> complex_;
  // dense
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> jacobian_;
  Eigen::MatrixXd real_matrix_;
  Eigen::MatrixXcd complex_matrix_;
  Eigen::PartialPivLU<Eigen::MatrixXd> real_lu_;
  Eigen::PartialPivLU<Eigen::MatrixXcd> complex_lu_;
};

/// One trajectory of an AdaptiveSystem as a RadauProblem (rkhs/adaptive/radau.hpp): one
/// column, the system's own right-hand side, and its stage solves.
class TrajectoryStages {
 public:
  TrajectoryStages(AdaptiveSystem& system, LinearSolver solver)
      : system_(system), solves_(system, solver) {}
  Eigen::Index rows() const { return system_.dimension(); }
  Eigen::Index columns() const { return 1; }
  void rhs(double t, const Eigen::MatrixXd& z, Eigen::MatrixXd& dz) {
    system_.rhs(z.data(), dz.data(), t);
  }
  void factor(double t, const Eigen::MatrixXd& z, double real_shift,
              std::complex<double> complex_shift) {
    solves_.factor(t, z.data(), real_shift, complex_shift);
  }
  void solve_real(Eigen::MatrixXd& r) const { solves_.solve_real(r); }
  void solve_complex(Eigen::MatrixXcd& r) const { solves_.solve_complex(r); }

 private:
  AdaptiveSystem& system_;
  StageSolves solves_;
};

}  // namespace rkhs
