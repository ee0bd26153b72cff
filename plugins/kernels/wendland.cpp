#include "rkhs/kernels/wendland.hpp"

#include <fmt/format.h>

#include "rkhs/kernel/kernel_algorithms.hpp"

namespace rkhs::kernels {

PluginInfo Wendland::info() {
  return {
      "wendland",
      "Wendland's compactly supported function phi_{d,k}(|x - y| / radius), d = 1, 2, 3",
      {integer_parameter("k", 1,
                         "smoothness k (phi is C^{2k}); Sobolev order tau = k + (d + 1)/2", 0, 3),
       positive_parameter("radius", 1.0, "support radius rho, metres")},
      {{"periodic", "by images (finite sum, exact)"}},
  };
}

Wendland::Wendland(const ParameterSet& parameters, const Domain& domain)
    : smoothness_(static_cast<int>(parameters.integer("k"))),
      radius_(parameters.real("radius")),
      domain_(domain) {
  if (smoothness_ < 0 || smoothness_ > 3)
    throw ParameterError("k", "parameter 'k' must be in [0, 3]");
  if (!(radius_ > 0) || !std::isfinite(radius_))
    throw ParameterError("radius", "parameter 'radius' must be > 0 and finite");
  // Image m is at distance >= (|m| - 1/2) L from x when |d| <= L/2: beyond this none reaches.
  // The sums are bounded before anything is converted to int (a radius of 2^31 periods was
  // undefined behaviour and no periodisation at all).
  if (domain_.periodic) {
    double terms = 1.0;  // images summed per evaluation, prod_a (2 M_a + 1)
    for (int a = 0; a < domain_.dimension; ++a)
      terms *= 2.0 * std::ceil(radius_ / domain_.extent(a) + 0.5) + 1.0;
    if (domain_.dimension == 1 ? !(radius_ / domain_.length <= max_periods)
                               : !(terms <= max_image_terms)) {
      if (domain_.dimension == 1)
        throw ParameterError(
            "radius",
            fmt::format("parameter 'radius' must be at most {} times the length of a periodic "
                        "track (a kernel value sums 2 ceil(radius / L + 1/2) + 1 images), found "
                        "radius = {} on a track of length {}",
                        max_periods, format_real(radius_), format_real(domain_.length)));
      throw ParameterError(
          "radius",
          fmt::format("parameter 'radius' = {} would sum {:.4g} images per kernel value on this "
                      "torus (prod over the axes of 2 ceil(radius / L_a + 1/2) + 1), more than "
                      "{}: the radius must be smaller against the periods",
                      format_real(radius_), terms, max_image_terms));
    }
    images_ = static_cast<int>(std::ceil(radius_ / domain_.length + 0.5));
    for (int a = 0; a < domain_.dimension; ++a)
      axis_images_[a] = static_cast<int>(std::ceil(radius_ / domain_.extent(a) + 0.5));
  }
}

KernelProperties Wendland::properties() const noexcept {
  KernelProperties p;
  p.positive_definite = true;
  p.sobolev_order = smoothness_ + (domain_.dimension + 1) / 2.0;
  p.dimension = domain_.dimension;
  p.support_radius = radius_;
  p.stationary = true;
  p.periodic = domain_.periodic;
  return p;
}

}  // namespace rkhs::kernels

RKHS_REGISTER_KERNEL(rkhs::kernels::Wendland)
