#include "rkhs/rates/rates.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <boost/math/distributions/students_t.hpp>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace rkhs {
namespace {

constexpr double not_a_number = std::numeric_limits<double>::quiet_NaN();

bool positive_finite(double v) {
  return std::isfinite(v) && v > 0.0;
}

void require_same_size(std::span<const double> x, std::span<const double> y, const char* who) {
  if (x.size() != y.size())
    throw std::invalid_argument(
        fmt::format("{}: x has {} points but y has {}", who, x.size(), y.size()));
}

// Mean of v, refined by one correction pass (the first pass's rounding error is removed).
double careful_mean(const std::vector<double>& v) {
  double sum = 0.0;
  for (double e : v) sum += e;
  const double first = sum / static_cast<double>(v.size());
  double correction = 0.0;
  for (double e : v) correction += e - first;
  return first + correction / static_cast<double>(v.size());
}

// The one regression core behind both models: ln y = intercept + rate u(x).
std::optional<RateFit> fit_log_linear(std::span<const double> x, std::span<const double> y,
                                      double confidence, RateModel model, const char* who) {
  require_same_size(x, y, who);
  if (!(confidence > 0.0 && confidence < 1.0))
    throw std::invalid_argument(
        fmt::format("{}: confidence must lie in (0, 1), got {}", who, confidence));

  const bool power_law = model == RateModel::power_law;
  RateFit fit;
  fit.model = model;
  fit.confidence = confidence;

  // Screen the points; count the reasons for exclusion (a point counts once, for its first).
  std::size_t bad_x = 0, nonfinite_y = 0, nonpositive_y = 0;
  std::vector<double> u, v;
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (power_law ? !positive_finite(x[i]) : !std::isfinite(x[i])) {
      ++bad_x;
    } else if (!std::isfinite(y[i])) {
      ++nonfinite_y;
    } else if (y[i] <= 0.0) {
      ++nonpositive_y;
    } else {
      fit.used.push_back(i);
      u.push_back(power_law ? std::log(x[i]) : x[i]);
      v.push_back(std::log(y[i]));
    }
  }
  const std::size_t m = fit.used.size();
  fit.points = m;

  std::vector<std::string> notes;
  if (m < x.size()) {
    std::vector<std::string> reasons;
    if (bad_x > 0)
      reasons.push_back(fmt::format("{} with {} abscissa", bad_x,
                                    power_law ? "non-finite, zero or negative" : "non-finite"));
    if (nonfinite_y > 0) reasons.push_back(fmt::format("{} with non-finite value", nonfinite_y));
    if (nonpositive_y > 0)
      reasons.push_back(fmt::format("{} with zero or negative value", nonpositive_y));
    notes.push_back(fmt::format("excluded {} of {} points: {}", x.size() - m, x.size(),
                                fmt::join(reasons, ", ")));
  }
  if (m < 2) return std::nullopt;
  bool spread = false;
  for (double e : u) spread = spread || e != u.front();
  if (!spread) return std::nullopt;

  const double u_mean = careful_mean(u);
  const double v_mean = careful_mean(v);
  double suu = 0.0, suv = 0.0, svv = 0.0;
  for (std::size_t k = 0; k < m; ++k) {
    const double du = u[k] - u_mean, dv = v[k] - v_mean;
    suu += du * du;
    suv += du * dv;
    svv += dv * dv;
  }
  fit.rate = suv / suu;
  fit.intercept = v_mean - fit.rate * u_mean;

  // Residuals from the centred form, so SSE is not the difference of two large numbers.
  double sse = 0.0;
  for (std::size_t k = 0; k < m; ++k) {
    const double r = (v[k] - v_mean) - fit.rate * (u[k] - u_mean);
    sse += r * r;
  }
  fit.r_squared = svv > 0.0 ? 1.0 - sse / svv : not_a_number;
  if (!(svv > 0.0)) notes.push_back("all used values are equal: R² undefined");

  if (m == 2) {
    fit.std_error = fit.ci_low = fit.ci_high = fit.residual_std = not_a_number;
    notes.push_back("only 2 points: slope exact, no standard error or confidence interval");
  } else {
    const double dof = static_cast<double>(m - 2);
    fit.residual_std = std::sqrt(sse / dof);
    fit.std_error = fit.residual_std / std::sqrt(suu);
    const boost::math::students_t t(dof);
    const double half_width = boost::math::quantile(t, 0.5 + 0.5 * confidence) * fit.std_error;
    fit.ci_low = fit.rate - half_width;
    fit.ci_high = fit.rate + half_width;
  }
  fit.note = fmt::format("{}", fmt::join(notes, "; "));
  return fit;
}

}  // namespace

std::vector<double> pairwise_rates(std::span<const double> x, std::span<const double> y) {
  require_same_size(x, y, "pairwise_rates");
  std::vector<double> rates;
  for (std::size_t i = 1; i < x.size(); ++i) {
    const bool defined = positive_finite(x[i - 1]) && positive_finite(x[i]) &&
                         positive_finite(y[i - 1]) && positive_finite(y[i]) && x[i] != x[i - 1];
    rates.push_back(defined ? std::log(y[i] / y[i - 1]) / std::log(x[i] / x[i - 1]) : not_a_number);
  }
  return rates;
}

std::optional<RateFit> fit_power_law(std::span<const double> x, std::span<const double> y,
                                     double confidence) {
  return fit_log_linear(x, y, confidence, RateModel::power_law, "fit_power_law");
}

std::optional<RateFit> fit_exponential(std::span<const double> x, std::span<const double> y,
                                       double confidence) {
  return fit_log_linear(x, y, confidence, RateModel::exponential, "fit_exponential");
}

double log_sse_floor(double sse, double relative_floor_norm) {
  if (!(relative_floor_norm > 0.0)) return 0.0;
  const double share = relative_floor_norm / std::sqrt(std::max(sse, 0.0));
  return share < 1.0 ? -2.0 * std::log1p(-share) : std::numeric_limits<double>::infinity();
}

FitFloors fit_floors(const RateFit& fit, std::span<const double> u, std::span<const double> y,
                     std::span<const double> floors) {
  FitFloors out;
  const std::size_t m = fit.used.size();
  if (m < 2) return out;
  std::vector<double> relative(m);
  double u_mean = 0.0, v_mean = 0.0;
  for (std::size_t k = 0; k < m; ++k) {
    const auto i = fit.used[k];
    const double floor = i < floors.size() && floors[i] > 0.0 ? floors[i] : 0.0;
    relative[k] = floor / std::abs(y[i]);
    u_mean += u[i] / static_cast<double>(m);
    v_mean += std::log(y[i]) / static_cast<double>(m);
  }
  double suu = 0.0, sst = 0.0, norm_squared = 0.0, slope_shift = 0.0;
  for (std::size_t k = 0; k < m; ++k) {
    const auto i = fit.used[k];
    suu += (u[i] - u_mean) * (u[i] - u_mean);
    sst += (std::log(y[i]) - v_mean) * (std::log(y[i]) - v_mean);
    norm_squared += relative[k] * relative[k];
  }
  if (!(suu > 0.0) || norm_squared == 0.0) return out;
  for (std::size_t k = 0; k < m; ++k)
    slope_shift += std::abs((u[fit.used[k]] - u_mean) / suu) * relative[k];
  const double norm = std::sqrt(norm_squared);
  out.rate = slope_shift;
  if (m > 2) {
    const double degrees = static_cast<double>(m - 2);
    const double t_quantile = std::isfinite(fit.std_error) && fit.std_error > 0.0
                                  ? (fit.ci_high - fit.rate) / fit.std_error
                                  : 0.0;
    out.rate += t_quantile * norm / std::sqrt(degrees * suu);
    const double sse = fit.residual_std * fit.residual_std * degrees;
    out.log_sse = log_sse_floor(sse, norm);
    // |r + P d| <= |r| + |d|: SSE and SST move by at most 2 |d| sqrt(S) + |d|^2.
    const double sse_shift = 2.0 * norm * std::sqrt(sse) + norm_squared;
    const double sst_shift = 2.0 * norm * std::sqrt(sst) + norm_squared;
    out.r_squared = sst > 0.0 ? sse_shift / sst + sse * sst_shift / (sst * sst)
                              : std::numeric_limits<double>::quiet_NaN();
  }
  return out;
}

}  // namespace rkhs
