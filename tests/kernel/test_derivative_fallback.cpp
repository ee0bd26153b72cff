// Derivatives of a kernel type without a closed form: DerivativeStencil's difference quotient
// (step 1e-7 L, one-sided next to a kink point and at an interval's ends), the same values from
// AnyKernel::derivative and from both kinds of basis.

#include <Eigen/Dense>
#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "rkhs/kernel/kernel.hpp"
#include "rkhs/kernel/kernel_algorithms.hpp"

namespace {

using rkhs::DerivativeStencil;
using rkhs::Domain;

// A Gaussian of width 0.8 with no derivative(): the fallback's subject.
struct PlainGaussian {
  static rkhs::PluginInfo info() { return {"plain_gaussian", "test kernel", {}, {}}; }
  PlainGaussian(const rkhs::ParameterSet&, const Domain& domain) : domain_(domain) {}
  double operator()(double x, double y) const noexcept {
    const double d = domain_.difference(x, y);
    return std::exp(-d * d / (2 * 0.64));
  }
  rkhs::KernelProperties properties() const noexcept {
    rkhs::KernelProperties p;
    p.analytic = true;
    p.periodic = domain_.periodic;
    return p;
  }
  Domain domain_;
};

// Rank one, k(x, y) = g(x) g(y) with g(s) = 1 + |s - 2|: a kink at s = 2, declared; piecewise
// linear, so every difference quotient on one side of the kink is exact up to rounding.
struct Kinked {
  static rkhs::PluginInfo info() { return {"kinked", "test kernel", {}, {}}; }
  Kinked(const rkhs::ParameterSet&, const Domain&) {}
  static double g(double s) noexcept { return 1.0 + std::abs(s - 2.0); }
  double operator()(double x, double y) const noexcept { return g(x) * g(y); }
  rkhs::KernelProperties properties() const noexcept {
    rkhs::KernelProperties p;
    p.positive_definite = false;
    p.stationary = false;
    return p;
  }
  std::vector<double> kink_points() const { return {2.0}; }
};

// The same kernel through a one-feature map, without feature derivatives.
struct KinkedFeatures : Kinked {
  static rkhs::PluginInfo info() { return {"kinked_features", "test kernel", {}, {}}; }
  using Kinked::Kinked;
  void features(double s, rkhs::SparseFeatures& out) const {
    out.clear();
    out.push(0, g(s));
  }
  std::size_t feature_count() const noexcept { return 1; }
};

}  // namespace

TEST_CASE("DerivativeStencil: central with step 1e-7 L, one-sided next to kinks and ends",
          "[kernel][derivative]") {
  const Domain interval{5.0, false};
  const DerivativeStencil stencil(interval, {2.0});
  const double h = 1e-7 * 5.0;
  CHECK(stencil.step() == h);
  auto line = [](double s) { return 3.0 * s - 1.0; };
  auto square = [](double s) { return s * s; };
  CHECK(stencil.at(1.0).size == 2);
  CHECK(stencil.apply(square, 1.0) == Approx(2.0).epsilon(1e-8));
  // At the kink and just right of it: forward; just left of it: backward.
  for (double s : {2.0, 2.0 + 0.5 * h, 2.0 - 0.5 * h}) {
    const auto at = stencil.at(s);
    INFO("s - 2 = " << s - 2.0);
    CHECK(at.size == 3);
    CHECK(at.point[0] == s);
    CHECK((at.point[2] > s) == (s >= 2.0));
    CHECK(stencil.apply(line, s) == Approx(3.0).epsilon(1e-8));
    CHECK(stencil.apply(square, s) == Approx(2 * s).epsilon(1e-8));  // second order: exact on s^2
  }
  // The interval's ends: inward, never outside [0, L].
  CHECK(stencil.at(0.0).point[2] > 0.0);
  CHECK(stencil.at(5.0).point[2] < 5.0);
  CHECK(stencil.apply(square, 5.0) == Approx(10.0).epsilon(1e-8));

  // On a track, a kink at 0 is seen across the seam.
  const Domain track{5.0, true};
  const DerivativeStencil periodic(track, {0.0});
  CHECK(periodic.at(5.0 - 0.5 * h).point[2] < 5.0 - 0.5 * h);  // just left of the seam: backward
  CHECK(periodic.at(0.5 * h).point[2] > 0.5 * h);              // just right: forward
  CHECK(periodic.at(2.5).size == 2);
}

TEST_CASE("a kernel without derivative(): differences, the same from AnyKernel and its basis",
          "[kernel][derivative]") {
  const Domain track{12.0, true};
  const rkhs::KernelModel<PlainGaussian> kernel(rkhs::ParameterSet{}, track);
  CHECK_FALSE(kernel.has_exact_derivative());
  for (double c : {1.0, 6.0}) {
    for (double s : {0.5, 1.0, 1.7, 5.0, 11.9}) {
      const double d = track.difference(c, s);
      const double exact = d / 0.64 * std::exp(-d * d / (2 * 0.64));
      INFO("c = " << c << ", s = " << s);
      // Error bound of DerivativeStencil: below 2e-8 of the slope scale k / sigma.
      CHECK(kernel.derivative(c, s) == Approx(exact).margin(2e-8 / 0.8));
    }
  }
  const std::vector<double> centres{0.5, 3.0, 7.25, 11.0};
  const auto basis = kernel.basis(centres);
  Eigen::VectorXd dphi(4), mapped(2);
  Eigen::MatrixXd map(2, 4);
  map << 1, -2, 0.5, 3, 0, 1, 1, -1;
  basis->set_map(map);
  for (double s : {0.0, 0.5, 4.4, 11.99}) {
    basis->evaluate_derivative(s, dphi.data());
    for (std::size_t i = 0; i < centres.size(); ++i)
      CHECK(dphi(static_cast<Eigen::Index>(i)) == kernel.derivative(centres[i], s));
    basis->evaluate_mapped_derivative(s, mapped.data());
    CHECK((mapped - map * dphi).cwiseAbs().maxCoeff() <= 1e-15);
  }
}

TEST_CASE("a kernel with a kink point and no derivative(): one-sided at the kink, both bases",
          "[kernel][derivative]") {
  const Domain interval{5.0, false};
  const rkhs::KernelModel<Kinked> direct(rkhs::ParameterSet{}, interval);
  const rkhs::KernelModel<KinkedFeatures> featured(rkhs::ParameterSet{}, interval);
  CHECK_FALSE(direct.has_exact_derivative());
  CHECK_FALSE(featured.has_exact_derivative());
  const double h = 1e-7 * 5.0;
  // d/dy g(x) g(y) = g(x) sign(y - 2), the right-hand value +g(x) at the kink.
  const double x = 4.0, gx = Kinked::g(x);
  for (const rkhs::AnyKernel* kernel : {static_cast<const rkhs::AnyKernel*>(&direct),
                                        static_cast<const rkhs::AnyKernel*>(&featured)}) {
    CHECK(kernel->derivative(x, 2.0) == Approx(gx).epsilon(1e-8));
    CHECK(kernel->derivative(x, 2.0 + 0.3 * h) == Approx(gx).epsilon(1e-8));
    CHECK(kernel->derivative(x, 2.0 - 0.3 * h) == Approx(-gx).epsilon(1e-8));
    CHECK(kernel->derivative(x, 1.0) == Approx(-gx).epsilon(1e-8));
    CHECK(kernel->derivative(x, 0.0) == Approx(-gx).epsilon(1e-8));  // inward at the end
    CHECK(kernel->derivative(x, 5.0) == Approx(gx).epsilon(1e-8));
    const std::vector<double> centres{x, 1.0};
    const auto basis = kernel->basis(centres);
    basis->set_map(Eigen::MatrixXd::Identity(2, 2) * 3.0);
    double dphi[2], mapped[2];
    for (double s : {0.0, 2.0, 2.0 - 0.3 * h, 3.0, 5.0}) {
      basis->evaluate_derivative(s, dphi);
      basis->evaluate_mapped_derivative(s, mapped);
      for (int i = 0; i < 2; ++i) {
        INFO(kernel->name() << ", s = " << s << ", centre " << centres[i]);
        // The feature basis differences features (and mapped features), rounded unlike k and
        // 3 phi: the quotient amplifies that rounding, eps |k| / h ~ 1e-9 here.
        CHECK(dphi[i] == Approx(kernel->derivative(centres[i], s)).margin(1e-8));
        CHECK(mapped[i] == Approx(3.0 * dphi[i]).margin(3e-8));
      }
    }
  }
}
