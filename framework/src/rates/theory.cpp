#include "rkhs/rates/theory.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "rkhs/approx/metrics.hpp"
#include "rkhs/core/parameters.hpp"

namespace rkhs {

const std::vector<std::string>& theory_metrics() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const auto& row : MetricTable<ApproximationMetric>::rows)
      if (row.theory != TheoryLaw::none) out.emplace_back(row.name);
    return out;
  }();
  return names;
}

std::string no_theory_law(std::string_view metric) {
  return fmt::format("no theory rate for metric '{}' (theory covers {})", metric,
                     fmt::join(theory_metrics(), ", "));
}

std::optional<TheoryRate> theory_rate(std::string_view metric, const KernelProperties& properties,
                                      std::string* why) {
  for (const auto& row : MetricTable<ApproximationMetric>::rows)
    if (row.name == metric && row.theory != TheoryLaw::none)
      return theory_rate(row, properties, why);
  if (why) *why = no_theory_law(metric);
  return std::nullopt;
}

std::optional<TheoryRate> theory_rate(const MetricInfo& row, const KernelProperties& properties,
                                      std::string* why) {
  const int dimension = properties.dimension;
  const std::string_view metric = row.name;
  const TheoryLaw law = row.theory;
  auto none = [&](std::string reason) -> std::optional<TheoryRate> {
    if (why) *why = std::move(reason);
    return std::nullopt;
  };
  if (law == TheoryLaw::none) return none(no_theory_law(metric));
  TheoryRate theory;
  theory.dimension = dimension;
  if (law == TheoryLaw::level_reduction) {
    if (properties.analytic || !properties.sobolev_order)
      return none(fmt::format(
          "the multiscale theorem bounding {} (Wendland 2010) is stated for kernels of finite "
          "smoothness, equivalent to a Sobolev space H^tau with tau > d/2; this kernel {}",
          metric, properties.analytic ? "is analytic" : "gives no sobolev_order in its metadata"));
    theory.h_exponent = 0.0;
    theory.sharp = false;
    theory.values_below = 1.0;
    theory.quasi_uniform_because = "the theorem is stated for quasi-uniform nested centre sets";
    theory.statement = fmt::format(
        "{} <= alpha < 1 at every level, alpha independent of the level (multiscale "
        "interpolation with rho_l = nu h_l, nu large enough; tau = {}, d = {})",
        metric, format_real(*properties.sobolev_order), dimension);
    return theory;
  }
  if (properties.analytic) {
    theory.model = RateModel::exponential;
    theory.sharp = false;
    theory.direction = law == TheoryLaw::gram_condition_number ? +1 : -1;
    theory.statement = fmt::format("{} {} at least exponentially in n (analytic kernel)", metric,
                                   theory.direction < 0 ? "decays" : "grows");
    return theory;
  }
  if (!properties.sobolev_order)
    return none("the kernel is neither analytic nor Sobolev-equivalent (its metadata gives no "
                "sobolev_order), so theory predicts no rate");
  const double tau = *properties.sobolev_order, d = dimension;
  const auto given = fmt::format("tau = {}, d = {}", format_real(tau), dimension);
  theory.holds_for_any_centres = law == TheoryLaw::power_function ||
                                 law == TheoryLaw::error_sup_bound ||
                                 law == TheoryLaw::error_l2_bound;
  if (law == TheoryLaw::power_function || law == TheoryLaw::error_sup_bound) {
    theory.h_exponent = tau - d / 2;
    theory.sharp = law == TheoryLaw::power_function;
    theory.statement = fmt::format("{} {} h^(tau - d/2) = h^{} ({})", metric,
                                   theory.sharp ? "~" : "<= C", format_real(theory.h_exponent), given);
  } else if (law == TheoryLaw::projection_norm) {
    // ||I - Pi||_{H -> C}: the power function for the H-orthogonal projection; within constants
    // of it for a uniformly bounded local projection onto a space of mesh h (docs/projections.md).
    theory.h_exponent = tau - d / 2;
    theory.statement = fmt::format(
        "{} ~ h^(tau - d/2) = h^{} ({}; a uniformly bounded projection onto a space of mesh h)",
        metric, format_real(theory.h_exponent), given);
  } else if (law == TheoryLaw::error_l2_bound) {
    theory.h_exponent = tau;
    theory.sharp = false;
    theory.statement = fmt::format("{} <= C h^tau = h^{} ({})", metric, format_real(tau), given);
  } else if (law == TheoryLaw::gram_min_eigenvalue) {
    theory.h_exponent = 2 * tau - d;
    theory.statement = fmt::format("{} ~ q^(2 tau - d) = q^{} ({}; q ~ h)", metric,
                                   format_real(theory.h_exponent), given);
  } else {  // gram_condition_number: lambda_max ~ n times 1 / lambda_min ~ q^-(2 tau - d)
    theory.h_exponent = -2 * tau;
    theory.statement = fmt::format(
        "{} ~ n q^-(2 tau - d) = h^{} ({}; lambda_max ~ n, lambda_min ~ q^(2 tau - d), q ~ h "
        "~ n^-1/d)",
        metric, format_real(theory.h_exponent), given);
  }
  return theory;
}

RateInterval theory_interval(const TheoryRate& theory, Abscissa abscissa, double tolerance,
                             double* slope) {
  const int dimension = theory.dimension;
  constexpr double infinity = std::numeric_limits<double>::infinity();
  // Against ln h the slope is the exponent; against ln n (h ~ n^-1/d) it is -exponent / d, and
  // "converges at least as fast" flips from slope >= to slope <=.
  const bool in_h = abscissa == Abscissa::fill_distance;
  const double predicted = in_h ? theory.h_exponent : -theory.h_exponent / dimension;
  if (slope) *slope = predicted;
  if (theory.sharp) return {predicted - tolerance, predicted + tolerance};
  return in_h ? RateInterval{predicted - tolerance, infinity}
              : RateInterval{-infinity, predicted + tolerance};
}

}  // namespace rkhs
