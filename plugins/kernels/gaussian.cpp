#include "rkhs/kernels/gaussian.hpp"

#include <fmt/format.h>

#include "rkhs/kernel/kernel_algorithms.hpp"

namespace rkhs::kernels {

PluginInfo Gaussian::info() {
  return {
      "gaussian",
      "Gaussian exp(-d^2/(2 sigma^2)), periodised by images on a closed track",
      {positive_parameter("sigma", 1.0, "width sigma, metres"),
       choice_parameter("convention", "2sigma2",
                        "\"2sigma2\": exp(-d^2/(2 sigma^2)) (paper Sec. 5); "
                        "\"sigma2\": exp(-d^2/sigma^2) (paper Sec. 2)",
                        {"2sigma2", "sigma2"})},
      {{"periodic", "by images, truncated below 1e-16 k(0)"}},
  };
}

Gaussian::Gaussian(const ParameterSet& parameters, const Domain& domain)
    : sigma_(parameters.real("sigma")), domain_(domain) {
  if (!(sigma_ > 0) || !std::isfinite(sigma_))
    throw ParameterError("sigma", "parameter 'sigma' must be > 0 and finite");
  const double factor = parameters.choice("convention") == "sigma2" ? 1.0 : 2.0;
  inverse_scale_ = 1.0 / (factor * sigma_ * sigma_);
  // The truncated image sum needs M ~ 7 to 10 sigma / L images each side: bounded before
  // image_count runs (sigma / L = 1e12 on a track of 1e-12 m summed its cap of 2^20 images
  // each side, 2 million exponentials per kernel value, without reaching the tolerance).
  if (domain_.periodic)
    for (int a = 0; a < domain_.dimension; ++a) {
      const double period = domain_.extent(a);
      if (!(sigma_ / period <= max_periods))
        throw ParameterError(
            "sigma",
            fmt::format("parameter 'sigma' must be at most {} times the period of a periodic "
                        "domain (beyond, a kernel value would sum more than 2^21 images; the "
                        "kernel is constant to double precision from sigma / L ~ 2 on), found "
                        "sigma = {} on a period of {}",
                        max_periods, format_real(sigma_), format_real(period)));
    }
  if (domain_.periodic)
    images_ = rkhs::kernels::image_count([this](double r) { return profile(r); }, domain_.length,
                                         image_tolerance);
  if (domain_.periodic && domain_.dimension > 1)
    for (int a = 0; a < domain_.dimension; ++a)
      axis_images_[a] = rkhs::kernels::image_count([this](double r) { return profile(r); },
                                                   domain_.extent(a), image_tolerance);
}

KernelProperties Gaussian::properties() const noexcept {
  KernelProperties p;
  p.positive_definite = true;
  p.analytic = true;
  p.support_radius = 0.0;
  p.stationary = true;
  p.periodic = domain_.periodic;
  p.dimension = domain_.dimension;
  return p;
}

}  // namespace rkhs::kernels

RKHS_REGISTER_KERNEL(rkhs::kernels::Gaussian)
