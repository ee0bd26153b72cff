#pragma once
// The Matern kernel with half-integer smoothness, in scikit-learn's parametrisation
// (sklearn.gaussian_process.kernels.Matern), d = |x - y|, l = length_scale:
//
//   nu = 0.5:  exp(-d/l)
//   nu = 1.5:  (1 + sqrt(3) d/l) exp(-sqrt(3) d/l)
//   nu = 2.5:  (1 + sqrt(5) d/l + 5 d^2 / (3 l^2)) exp(-sqrt(5) d/l)
//
// Parameters (study-file keys and CSV columns):
//   nu            one of 0.5, 1.5, 2.5, default 1.5: the smoothness.
//   length_scale  > 0, metres, default 1.
// Interval domain: k = k0. Periodic domain: sum of images k0(d + m L), truncated where the
// omitted images (polynomial factor included) are below 1e-16 k0(0); the image count is computed
// once by the constructor and grows like length_scale / L.
// Properties: strictly positive definite, native space H^{nu + 1/2} (d = 1), global support,
// stationary.
// Fails: ParameterError naming "nu" for any other nu (also checked by the declaration).

#include <cmath>

#include "rkhs/domain.hpp"
#include "rkhs/kernel.hpp"
#include "rkhs/kernels/periodic_images.hpp"
#include "rkhs/parameters.hpp"
#include "rkhs/registry.hpp"

namespace rkhs::kernels {

class Matern {
 public:
  static PluginInfo info();

  Matern(const ParameterSet& parameters, const Domain& domain);

  /// k0 at distance `distance` >= 0.
  double profile(double distance) const noexcept {
    const double a = distance * rate_;  // sqrt(2 nu) d / l
    switch (order_) {
      case 0: return std::exp(-a);
      case 1: return (1.0 + a) * std::exp(-a);
      default: return (1.0 + a + a * a * (1.0 / 3.0)) * std::exp(-a);
    }
  }

  double operator()(double x, double y) const noexcept {
    if (!domain_.periodic) return profile(std::abs(x - y));
    return sum_of_images([this](double r) { return profile(r); }, domain_.difference(x, y),
                         domain_.length, images_);
  }

  KernelProperties properties() const noexcept;

  double nu() const noexcept { return nu_; }
  int image_count() const noexcept { return images_; }

 private:
  double nu_;
  double length_scale_;
  int order_;    ///< nu - 1/2
  double rate_;  ///< sqrt(2 nu) / length_scale
  Domain domain_;
  int images_ = 0;
};

}  // namespace rkhs::kernels
