#include "rkhs/kernels/bspline.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <limits>

#include "rkhs/kernel/kernel_algorithms.hpp"

namespace rkhs::kernels {

PluginInfo MultiscaleBSpline::info() {
  // r defaults to the degree: the declared default is a placeholder (NaN, printed as "= degree")
  // and the constructor reads r only when the study gave it.
  auto r = positive_parameter("r", std::numeric_limits<double>::quiet_NaN(),
                              "smoothness r: level j is weighted by 2^{j (d - 2r)}; Sobolev order tau = r for d/2 < r < degree + 1/2");
  r.default_doc = "= degree";
  return {
      "bspline",
      "multiscale B-spline kernel sum_j 2^{j(d-2r)} sum_k N_p(2^j u/h0 - k) N_p(2^j v/h0 - k) "
      "(tensor-product splines in d = 2, 3)",
      {integer_parameter("degree", 1, "spline degree p (1: hat, 2: quadratic)", 0, max_degree), r,
       integer_parameter("n0", 4, "cells on level 0, h0 = L / n0 (periodic: n0 >= degree + 1)", 1,
                         max_n0),
       integer_parameter("J", 6, "finest level", 0, max_level)},
      {{"periodic", "by wrapped indices"},
       {"features", "n0 (2^{J+1} - 1) periodic, + (J + 1) degree on an interval"}},
  };
}

MultiscaleBSpline::MultiscaleBSpline(const ParameterSet& parameters, const Domain& domain)
    : length_(domain.length), periodic_(domain.periodic), dimension_(domain.dimension) {
  for (int a = 0; a < dimension_; ++a) axis_length_[static_cast<std::size_t>(a)] = domain.extent(a);
  const auto degree = parameters.integer("degree");
  if (degree < 0 || degree > max_degree)
    throw ParameterError("degree", fmt::format("parameter 'degree' must be in [0, {}], found {}",
                                               max_degree, degree));
  degree_ = static_cast<int>(degree);

  const auto n0 = parameters.integer("n0");
  if (n0 < 1 || n0 > max_n0)
    throw ParameterError("n0",
                         fmt::format("parameter 'n0' must be in [1, {}], found {}", max_n0, n0));
  if (periodic_ && n0 < degree + 1)
    throw ParameterError(
        "n0", fmt::format("parameter 'n0' must be >= degree + 1 = {} on a periodic domain (a "
                          "spline of degree {} would overlap its own periodic copy), found {}",
                          degree + 1, degree, n0));
  n0_ = static_cast<int>(n0);

  const auto levels = parameters.integer("J");
  if (levels < 0 || levels > max_level)
    throw ParameterError(
        "J", fmt::format("parameter 'J' must be in [0, {}], found {}", max_level, levels));
  levels_ = static_cast<int>(levels);
  // The knots of every level are held in memory and every feature has an index: bounded
  // before anything is built (n0 = 8192, J = 16 has 1.07e9 and took 4 GB to validate).
  const std::int64_t knots =
      n0 * ((std::int64_t{2} << levels) - 1) + (periodic_ ? 0 : (levels + 1) * degree);
  if (knots > max_knots)
    throw ParameterError(
        "J", fmt::format("n0 = {} and J = {} give {} knots on an axis (n0 (2^(J+1) - 1){}), above "
                         "the {} (2^24) a B-spline kernel may have; lower J or n0",
                         n0, levels, knots, periodic_ ? "" : " + (J + 1) degree", max_knots));

  if (parameters.given("r")) {
    r_ = parameters.real("r");
    if (!(r_ > 0) || !std::isfinite(r_))
      throw ParameterError("r",
                           fmt::format("parameter 'r' must be > 0, found {}", format_real(r_)));
  } else if (degree_ == 0) {
    throw ParameterError("r",
                         "parameter 'r' defaults to degree, which is 0, but r must be > 0: "
                         "give r explicitly for degree = 0");
  } else {
    r_ = degree_;
  }

  offset_[0] = 0;
  for (int j = 0; j <= levels_; ++j) {
    scale_[j] = std::ldexp(1.0, j);
    weight_[j] = std::exp2(0.5 * j * (1.0 - 2.0 * r_));
    slope_weight_[j] = weight_[j] * scale_[j] * n0_ / length_;
    offset_[j + 1] = offset_[j] + (n0_ << j) + (periodic_ ? 0 : degree_);
    point_weight_[j] = std::exp2(j * (dimension_ - 2.0 * r_));
  }
}

KernelProperties MultiscaleBSpline::properties() const noexcept {
  KernelProperties p;
  p.positive_definite = false;
  if (r_ > 0.5 * dimension_ && r_ < degree_ + 0.5) p.sobolev_order = r_;
  p.analytic = false;
  double longest = 0.0;
  for (int a = 0; a < dimension_; ++a)
    longest = std::max(longest, axis_length_[static_cast<std::size_t>(a)]);
  p.support_radius = dimension_ == 1 ? (degree_ + 1) * length_ / n0_
                                     : std::sqrt(double(dimension_)) * (degree_ + 1) * longest / n0_;
  p.dimension = dimension_;
  p.stationary = false;
  p.periodic = periodic_;
  return p;
}

}  // namespace rkhs::kernels

RKHS_REGISTER_KERNEL(rkhs::kernels::MultiscaleBSpline)
