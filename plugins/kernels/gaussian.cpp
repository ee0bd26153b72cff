#include "rkhs/kernels/gaussian.hpp"

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
