#include "rkhs/rates/asymptotic.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "rkhs/core/parameters.hpp"

namespace rkhs {
namespace {

constexpr double not_a_number = std::numeric_limits<double>::quiet_NaN();
// The window rule's constants (docs/verification.md): a rate is off when it differs from the
// bulk rate by more than 10 % of it and by more than 4 noise standard deviations.
constexpr double relative_threshold = 0.1;
constexpr double noise_multiple = 4.0;
constexpr std::size_t minimum_window = 3;
constexpr double decisive_evidence = 2.0;

double median(std::vector<double> values) {
  const std::size_t half = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(half), values.end());
  const double upper = values[half];
  if (values.size() % 2 == 1) return upper;
  return 0.5 * (upper + *std::max_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(half)));
}

// Croux and Rousseeuw (1992): the MAD of few normal samples is biased low; these factors make
// 1.4826 MAD unbiased for the standard deviation at sample size k.
double mad_correction(std::size_t k) {
  static constexpr double small[] = {1.0, 1.0, 1.196, 1.495, 1.363, 1.206, 1.200, 1.140, 1.129, 1.107};
  if (k < std::size(small)) return small[k];
  return static_cast<double>(k) / (static_cast<double>(k) - 0.8);
}

// Noise in v: each interior point against the chord of its neighbours, scaled to unit variance
// under i.i.d. noise, then a robust scale. A smooth trend (a head or a floor bending in) barely
// shows in second differences, scatter does.
double noise_scale(std::span<const double> u, std::span<const double> v) {
  std::vector<double> residuals;
  for (std::size_t i = 1; i + 1 < u.size(); ++i) {
    const double a = (u[i + 1] - u[i]) / (u[i + 1] - u[i - 1]), b = 1.0 - a;
    residuals.push_back(std::fabs(v[i] - (a * v[i - 1] + b * v[i + 1])) /
                        std::sqrt(1.0 + a * a + b * b));
  }
  if (residuals.empty()) return 0.0;
  return mad_correction(residuals.size()) * 1.4826 * median(residuals);
}

// 2 decimals, 3 significant digits below 1: how the console tables print rates.
std::string rate_text(double r) {
  return std::fabs(r) >= 1.0 ? fmt::format("{:.2f}", r) : fmt::format("{:.3g}", r);
}

std::string rate_list(const std::vector<double>& rates) {
  std::string out;
  for (std::size_t i = 0; i < rates.size(); ++i) out += (i ? ", " : "") + rate_text(rates[i]);
  return out;
}

// Residual sum of squares of the least-squares line through (u_i, v_i), i in positions.
double line_sse(std::span<const double> u, std::span<const double> v,
                const std::vector<std::size_t>& positions) {
  const double m = static_cast<double>(positions.size());
  double u_mean = 0.0, v_mean = 0.0;
  for (auto i : positions) {
    u_mean += u[i] / m;
    v_mean += v[i] / m;
  }
  double suu = 0.0, suv = 0.0, svv = 0.0;
  for (auto i : positions) {
    suu += (u[i] - u_mean) * (u[i] - u_mean);
    suv += (u[i] - u_mean) * (v[i] - v_mean);
    svv += (v[i] - v_mean) * (v[i] - v_mean);
  }
  if (!(suu > 0.0)) return svv;
  double sse = 0.0;
  const double slope = suv / suu;
  for (auto i : positions) {
    const double r = (v[i] - v_mean) - slope * (u[i] - u_mean);
    sse += r * r;
  }
  return sse;
}

std::string_view model_name(RateModel model) {
  return model == RateModel::power_law ? "power law" : "exponential model";
}

}  // namespace

std::string label_range(std::span<const double> labels, const std::vector<std::size_t>& positions) {
  if (positions.empty()) return "";
  const auto first = format_real(labels[positions.front()]);
  if (positions.size() == 1) return first;
  return first + ".." + format_real(labels[positions.back()]);
}

std::vector<double> pairwise_exponential_rates(std::span<const double> n,
                                               std::span<const double> y) {
  if (n.size() != y.size())
    throw std::invalid_argument("pairwise_exponential_rates: n and y differ in size");
  std::vector<double> rates;
  for (std::size_t i = 1; i < n.size(); ++i) {
    const bool defined = std::isfinite(n[i - 1]) && std::isfinite(n[i]) && n[i] != n[i - 1] &&
                         std::isfinite(y[i - 1]) && std::isfinite(y[i]) && y[i - 1] > 0.0 &&
                         y[i] > 0.0;
    rates.push_back(defined ? std::log(y[i] / y[i - 1]) / (n[i] - n[i - 1]) : not_a_number);
  }
  return rates;
}

AsymptoticWindow detect_asymptotic_window(std::span<const double> u, std::span<const double> v,
                                          std::span<const double> labels) {
  if (u.size() != v.size() || u.size() != labels.size())
    throw std::invalid_argument("detect_asymptotic_window: u, v and labels differ in size");
  const std::size_t m = u.size();
  AsymptoticWindow window;
  window.bulk_rate = window.noise = not_a_number;
  std::vector<double> rates, steps;
  bool increasing = true, decreasing = true;
  for (std::size_t i = 0; i + 1 < m; ++i) {
    steps.push_back(u[i + 1] - u[i]);
    rates.push_back((v[i + 1] - v[i]) / steps.back());
    increasing = increasing && steps.back() > 0.0;
    decreasing = decreasing && steps.back() < 0.0;
  }
  const bool monotone = increasing || decreasing;

  std::size_t lo = 0, hi = m == 0 ? 0 : m - 1;
  // What the notes say: the excluded rates, the smallest threshold they exceeded and the bulk
  // rate they were measured against (of the pass that excluded them).
  std::vector<double> head_rates, floor_rates;
  double head_threshold = std::numeric_limits<double>::infinity(), floor_threshold = head_threshold;
  double head_bulk = not_a_number, floor_bulk = not_a_number;
  bool floor_collapsed = false;
  auto bulk_of = [&](std::size_t a, std::size_t b) {  // R and s on points a..b
    const std::vector<double> window_rates(rates.begin() + static_cast<std::ptrdiff_t>(a),
                                           rates.begin() + static_cast<std::ptrdiff_t>(b));
    return std::pair{median(window_rates), noise_scale(u.subspan(a, b - a + 1), v.subspan(a, b - a + 1))};
  };
  // Trimming stops when a window would drop below 3 points; at most m passes.
  for (std::size_t pass = 0; monotone && m > minimum_window && pass < m; ++pass) {
    if (hi - lo + 1 <= minimum_window) break;
    const auto [bulk, noise] = bulk_of(lo, hi);
    auto threshold = [&, bulk = bulk, noise = noise](std::size_t i) {
      return std::max({relative_threshold * std::fabs(bulk),
                       noise_multiple * std::sqrt(2.0) * noise / std::fabs(steps[i]), 1e-12});
    };
    const double sign = bulk > 0.0 ? 1.0 : (bulk < 0.0 ? -1.0 : 0.0);
    std::size_t new_hi = hi;
    while (sign != 0.0 && new_hi - lo + 1 > minimum_window &&
           sign * (bulk - rates[new_hi - 1]) > threshold(new_hi - 1)) {
      floor_rates.insert(floor_rates.begin(), rates[new_hi - 1]);
      floor_threshold = std::min(floor_threshold, threshold(new_hi - 1));
      floor_bulk = bulk;
      --new_hi;
    }
    // A floor can also hide behind a large noise estimate (a sharp corner between fast decay
    // and a flat tail inflates the second differences): two or more trailing rates that have
    // collapsed below 10 % of the bulk rate are a floor whatever the noise.
    if (new_hi == hi && sign != 0.0) {
      std::size_t run = 0;
      while (run < hi - lo && std::fabs(rates[hi - 1 - run]) <= relative_threshold * std::fabs(bulk)) ++run;
      run = std::min(run, hi - lo + 1 - minimum_window);
      if (run >= 2) {
        for (std::size_t k = 0; k < run; ++k) floor_rates.insert(floor_rates.begin(), rates[hi - 1 - k]);
        floor_bulk = bulk;
        floor_collapsed = true;
        new_hi = hi - run;
      }
    }
    std::size_t new_lo = lo;
    while (new_hi - new_lo + 1 > minimum_window &&
           std::fabs(rates[new_lo] - bulk) > threshold(new_lo)) {
      head_rates.push_back(rates[new_lo]);
      head_threshold = std::min(head_threshold, threshold(new_lo));
      head_bulk = bulk;
      ++new_lo;
    }
    if (new_lo == lo && new_hi == hi) break;
    lo = new_lo;
    hi = new_hi;
  }

  for (std::size_t i = 0; i < m; ++i) {
    if (i < lo) window.head.push_back(i);
    else if (i > hi) window.floor.push_back(i);
    else window.points.push_back(i);
  }
  if (m >= 2) std::tie(window.bulk_rate, window.noise) = bulk_of(lo, hi);

  std::vector<std::string> notes;
  if (!monotone && m >= 2)
    notes.push_back("abscissa not strictly monotone in n: no asymptotic window detected");
  if (!window.head.empty())
    notes.push_back(fmt::format(
        "head n = {} excluded (pairwise rate{} {} differ{} from the bulk rate {} by more than {})",
        label_range(labels, window.head), head_rates.size() > 1 ? "s" : "", rate_list(head_rates),
        head_rates.size() > 1 ? "" : "s", rate_text(head_bulk), rate_text(head_threshold)));
  if (!window.floor.empty())
    notes.push_back(fmt::format(
        "floor from n = {} excluded (pairwise rate{} {} stalled against the bulk rate {}{})",
        format_real(labels[window.floor.front()]), floor_rates.size() > 1 ? "s" : "",
        rate_list(floor_rates), rate_text(floor_bulk),
        floor_collapsed ? fmt::format(": below {} % of it", 100 * relative_threshold)
                        : fmt::format(" by more than {}", rate_text(floor_threshold))));
  for (std::size_t i = 0; i < notes.size(); ++i) window.note += (i ? "; " : "") + notes[i];
  return window;
}

std::string FitWindow::text() const {
  std::vector<std::string> parts;
  if (n_from) parts.push_back("n_from = " + format_real(*n_from));
  if (n_to) parts.push_back("n_to = " + format_real(*n_to));
  if (h_from) parts.push_back("h_from = " + format_real(*h_from));
  if (h_to) parts.push_back("h_to = " + format_real(*h_to));
  if (last) parts.push_back(fmt::format("last = {}", *last));
  std::string out;
  for (std::size_t i = 0; i < parts.size(); ++i) out += (i ? ", " : "") + parts[i];
  return out;
}

namespace {

// ΔAIC to one decimal, or to the digits its floor leaves ("~6" with a floor of 0.1 to 1, "~10"
// with one of 1 to 10, "unresolved" beyond): digits below the floor are not printed.
std::string evidence_text(double evidence, double floor) {
  if (!(floor >= 0.05)) return fmt::format("{:.1f}", evidence);
  if (!std::isfinite(floor) || floor >= std::abs(evidence)) return "unresolved (at the values' floors)";
  const int decade = static_cast<int>(std::ceil(std::log10(floor)));
  const double step = std::pow(10.0, decade);
  return fmt::format("~{:.{}f}", std::round(evidence / step) * step, std::max(0, -decade));
}

// Whether successive rates move the same way, each step no larger than the one before: a
// smooth approach to a limit, as a pre-asymptotic term C n^p D n^-q produces (not scatter).
bool bends_monotonically(const std::vector<double>& rates) {
  if (rates.size() < 3) return false;
  double previous_step = std::numeric_limits<double>::infinity(), sign = 0.0;
  for (std::size_t i = 0; i + 1 < rates.size(); ++i) {
    const double step = rates[i + 1] - rates[i];
    if (!std::isfinite(step) || step == 0.0) return false;
    const double step_sign = step > 0.0 ? 1.0 : -1.0;
    if (sign != 0.0 && step_sign != sign) return false;
    if (std::fabs(step) > previous_step) return false;
    sign = step_sign;
    previous_step = std::fabs(step);
  }
  return true;
}

}  // namespace

double ConstantSeries::relative_band() const {
  if (value != 0.0) return band / std::fabs(value);
  return band == 0.0 ? 0.0 : std::numeric_limits<double>::infinity();
}

std::string ConstantSeries::text(std::span<const double> labels) const {
  std::string out;
  if (band == 0.0 || !std::isfinite(band)) {
    out = fmt::format("{} ± 0", format_real(value));
  } else {
    // The digits of the value that the band leaves, and one more.
    const double ratio = value != 0.0 ? std::fabs(value) / band : 1.0;
    const int digits = std::clamp(static_cast<int>(std::ceil(std::log10(ratio))) + 1, 2, 17);
    out = fmt::format("{:#.{}g} ± {:.2g}", value, digits, band);
    if (out.find('.') != std::string::npos && out.find("e") == std::string::npos) {
      // "3.0 ± 0.1" rather than "3. ± 0.1" when the value ends at its point.
      auto dot = out.find(". ");
      if (dot != std::string::npos) out.erase(dot, 1);
    }
  }
  if (within_floors && band > 0.0)
    out += " (within the values' floors)";
  else if (band > 0.0 && value != 0.0)
    out += fmt::format(" ({:.2g} %)", 100.0 * relative_band());
  return out + fmt::format(" on n = {}", label_range(labels, points));
}

std::optional<ConstantSeries> detect_constant(std::span<const double> y,
                                              std::span<const double> floors,
                                              const std::vector<std::size_t>& points,
                                              double within) {
  if (points.size() < minimum_window) return std::nullopt;
  double low = std::numeric_limits<double>::infinity(), high = -low;
  // The intervals y_i +- floor_i share a point when the highest lower end is below the lowest
  // upper end; 4 ulps of slack, as values without a floor are known to their last bits.
  double highest_lower = -std::numeric_limits<double>::infinity(), lowest_upper = -highest_lower;
  double largest_floor = 0.0;
  for (auto p : points) {
    if (p >= y.size() || !std::isfinite(y[p])) return std::nullopt;
    const double floor = p < floors.size() && floors[p] > 0.0 ? floors[p] : 0.0;
    const double slack = floor + 4.0 * std::numeric_limits<double>::epsilon() * std::fabs(y[p]);
    low = std::min(low, y[p]);
    high = std::max(high, y[p]);
    highest_lower = std::max(highest_lower, y[p] - slack);
    lowest_upper = std::min(lowest_upper, y[p] + slack);
    largest_floor = std::max(largest_floor, floor);
  }
  ConstantSeries constant;
  constant.value = 0.5 * low + 0.5 * high;
  constant.band = 0.5 * high - 0.5 * low;
  constant.floor = largest_floor;
  constant.within = within;
  constant.within_floors = highest_lower <= lowest_upper;
  if (!constant.within_floors && !(constant.band <= within * std::fabs(constant.value)))
    return std::nullopt;
  constant.points = points;
  return constant;
}

namespace {

// Whether a point with this n and abscissa x lies inside the window the study set.
bool inside(const FitWindow& window, double n, double x) {
  return (!window.n_from || n >= *window.n_from) && (!window.n_to || n <= *window.n_to) &&
         (!window.h_from || x >= *window.h_from) && (!window.h_to || x <= *window.h_to);
}

// Keeps the last `window.last` of `points` when the window asks for them.
void keep_last(const FitWindow& window, std::vector<std::size_t>& points) {
  if (window.last && points.size() > *window.last)
    points.erase(points.begin(), points.end() - static_cast<std::ptrdiff_t>(*window.last));
}

// A series' points both models are fitted on, and their coordinates: the same points for both,
// so that their fits can be compared.
struct FittedPoints {
  std::span<const double> x, n, y, floors;
  std::vector<std::size_t> positions;         ///< usable, positive, inside the set window
  std::vector<double> log_x, log_y, plain_n;  ///< at `positions`

  double floor_at(std::size_t p) const {
    return p < floors.size() && floors[p] > 0.0 ? floors[p] : 0.0;
  }
  // `analysis`'s window as indices into `positions`.
  std::vector<std::size_t> window_of(const ModelAnalysis& analysis) const {
    std::vector<std::size_t> window;
    for (auto p : analysis.window.points)
      window.push_back(static_cast<std::size_t>(
          std::lower_bound(positions.begin(), positions.end(), p) - positions.begin()));
    return window;
  }
};

FittedPoints fitted_points(std::span<const double> x, std::span<const double> n,
                           std::span<const double> y, const std::vector<bool>& usable,
                           const FitWindow& set_window, std::span<const double> floors) {
  FittedPoints points{x, n, y, floors, {}, {}, {}, {}};
  for (std::size_t i = 0; i < y.size(); ++i)
    if (usable[i] && std::isfinite(y[i]) && y[i] > 0.0 && std::isfinite(x[i]) && x[i] > 0.0 &&
        std::isfinite(n[i]) && (set_window.empty() || inside(set_window, n[i], x[i])))
      points.positions.push_back(i);
  keep_last(set_window, points.positions);
  for (auto i : points.positions) {
    points.log_x.push_back(std::log(x[i]));
    points.log_y.push_back(std::log(y[i]));
    points.plain_n.push_back(n[i]);
  }
  return points;
}

// One model's window (automatic unless the study set one), fit, floors and pairwise rates.
ModelAnalysis analyse_model(RateModel model, const FittedPoints& points,
                            const FitWindow& set_window, double confidence) {
  ModelAnalysis result;
  result.model = model;
  const auto& positions = points.positions;
  const std::span<const double> u = model == RateModel::power_law ? points.log_x : points.plain_n;
  AsymptoticWindow window;
  if (set_window.empty()) {
    window = detect_asymptotic_window(u, points.log_y, points.plain_n);
  } else {
    for (std::size_t k = 0; k < positions.size(); ++k) window.points.push_back(k);
    window.bulk_rate = window.noise = not_a_number;
  }
  std::vector<double> fit_x, fit_y, fit_u, fit_floor_values;
  for (auto k : window.points) {
    const std::size_t p = positions[k];
    fit_x.push_back(model == RateModel::power_law ? points.x[p] : points.n[p]);
    fit_y.push_back(points.y[p]);
    fit_u.push_back(u[k]);
    fit_floor_values.push_back(p < points.floors.size() ? points.floors[p] : 0.0);
  }
  for (auto* indices : {&window.points, &window.head, &window.floor})
    for (auto& k : *indices) k = positions[k];
  result.window = std::move(window);
  result.fit = model == RateModel::power_law ? fit_power_law(fit_x, fit_y, confidence)
                                             : fit_exponential(fit_x, fit_y, confidence);
  if (result.fit) {
    result.floors = fit_floors(*result.fit, fit_u, fit_y, fit_floor_values);
    for (auto& k : result.fit->used) k = result.window.points[k];
  }
  result.pairwise = model == RateModel::power_law ? pairwise_rates(points.x, points.y)
                                                  : pairwise_exponential_rates(points.n, points.y);
  return result;
}

// ΔAIC of `analysis`'s model over the other on its own window.
double own_window_advantage(const FittedPoints& points, const ModelAnalysis& analysis) {
  const auto window = points.window_of(analysis);
  if (window.size() < minimum_window) return not_a_number;
  const double m = static_cast<double>(window.size());
  const double floor = m * 1e-20;  // exact series: a finite ratio instead of 0 / 0
  const double power = std::max(line_sse(points.log_x, points.log_y, window), floor);
  const double exponential = std::max(line_sse(points.plain_n, points.log_y, window), floor);
  const double ratio =
      analysis.model == RateModel::power_law ? exponential / power : power / exponential;
  return m * std::log(ratio);
}

// The floor of that ΔAIC: both models' ln SSE on the window, moved by the values' floors.
double own_window_advantage_floor(const FittedPoints& points, const ModelAnalysis& analysis) {
  const auto window = points.window_of(analysis);
  double norm_squared = 0.0;
  for (auto p : analysis.window.points) {
    const double floor = points.floor_at(p);
    norm_squared += (floor / points.y[p]) * (floor / points.y[p]);
  }
  if (window.size() < minimum_window || norm_squared == 0.0) return 0.0;
  const double norm = std::sqrt(norm_squared);
  return static_cast<double>(window.size()) *
         (log_sse_floor(line_sse(points.log_x, points.log_y, window), norm) +
          log_sse_floor(line_sse(points.plain_n, points.log_y, window), norm));
}

// Which model describes the series, with what evidence, and the sentence saying so.
void compare_models(const FittedPoints& points, SeriesAnalysis& out) {
  const double power_advantage = out.power_law.advantage =
      own_window_advantage(points, out.power_law);
  const double exponential_advantage = out.exponential.advantage =
      own_window_advantage(points, out.exponential);
  out.power_law.advantage_floor = own_window_advantage_floor(points, out.power_law);
  out.exponential.advantage_floor = own_window_advantage_floor(points, out.exponential);
  const double power_per_point = power_advantage / static_cast<double>(out.power_law.window.points.size());
  const double exponential_per_point =
      exponential_advantage / static_cast<double>(out.exponential.window.points.size());
  if (power_advantage > 0.0 && !(exponential_advantage > 0.0 && exponential_per_point > power_per_point)) {
    out.preferred = RateModel::power_law;
    out.evidence = power_advantage;
    out.evidence_points = out.power_law.window.points.size();
    out.evidence_floor = out.power_law.advantage_floor;
  } else if (exponential_advantage > 0.0) {
    out.preferred = RateModel::exponential;
    out.evidence = exponential_advantage;
    out.evidence_points = out.exponential.window.points.size();
    out.evidence_floor = out.exponential.advantage_floor;
  }
  out.reported = out.preferred == RateModel::exponential && out.decisive() ? RateModel::exponential
                                                                          : RateModel::power_law;
  if (out.preferred) {
    const auto& window = out.analysis(*out.preferred).window.points;
    const auto other = *out.preferred == RateModel::power_law ? RateModel::exponential
                                                              : RateModel::power_law;
    const auto why_not =
        out.evidence < decisive_evidence ? ", not decisive (ΔAIC < 2)"
        : out.evidence - out.evidence_floor < decisive_evidence
            ? ", not decisive (ΔAIC within its floor of 2: the values' floors decide it)"
        : out.evidence_points < 4 ? ", not decisive (a decision needs 4 points)"
                                  : "";
    out.note =
        fmt::format("{} preferred (ΔAIC = {} over the {} on n = {}){}", model_name(*out.preferred),
                    evidence_text(out.evidence, out.evidence_floor), model_name(other),
                    label_range(points.n, window), out.decisive() ? "" : why_not);
  } else if (std::isnan(power_advantage) || std::isnan(exponential_advantage)) {
    out.note = "models not compared (fewer than 3 points in a window)";
  } else {
    out.note = "neither model fits better on its own window";
  }
}

// The power law with a pre-asymptotic term on `candidate` (positions), with its floors, when
// the pairwise rates there bend monotonically; false when they do not or the fit fails.
bool try_bend(const FittedPoints& points, const std::vector<std::size_t>& candidate, bool upward,
              double confidence, SeriesAnalysis& out) {
  if (candidate.size() < 6) return false;
  std::vector<double> cx, cy;
  for (auto p : candidate) {
    cx.push_back(points.x[p]);
    cy.push_back(points.y[p]);
  }
  if (!bends_monotonically(pairwise_rates(cx, cy))) return false;
  auto fit = fit_power_law_corrected(cx, cy, upward, confidence);
  if (!fit) return false;
  // Its floors: refits with the values moved within them (both sign patterns).
  std::vector<double> relative;
  for (auto p : candidate) relative.push_back(points.floor_at(p) / points.y[p]);
  if (std::any_of(relative.begin(), relative.end(), [](double d) { return d > 0.0; })) {
    double mean_u = 0.0;
    for (double v : cx) mean_u += std::log(v) / static_cast<double>(cx.size());
    for (const double sign : {1.0, -1.0}) {
      std::vector<double> moved(cy);
      for (std::size_t k = 0; k < moved.size(); ++k)
        moved[k] *= 1.0 + sign * (std::log(cx[k]) >= mean_u ? 1.0 : -1.0) * relative[k];
      const auto refit = fit_power_law_corrected(cx, moved, upward, confidence);
      if (!refit) {
        out.corrected_floors = {std::numeric_limits<double>::infinity(),
                                std::numeric_limits<double>::infinity(),
                                std::numeric_limits<double>::infinity()};
        break;
      }
      auto& f = out.corrected_floors;
      for (double change :
           {refit->fit.rate - fit->fit.rate, refit->fit.std_error - fit->fit.std_error,
            refit->fit.ci_low - fit->fit.ci_low, refit->fit.ci_high - fit->fit.ci_high})
        if (std::isfinite(change)) f.rate = std::max(f.rate, std::abs(change));
      f.r_squared = std::max(f.r_squared, std::abs(refit->fit.r_squared - fit->fit.r_squared));
      f.log_sse = std::max(f.log_sse, std::abs(refit->advantage - fit->advantage));
    }
  }
  for (auto& k : fit->fit.used) k = candidate[k];
  out.corrected = std::move(fit);
  out.corrected_points = candidate;
  return true;
}

// A constant: every usable finite value (of the set window), any sign; else the power law's
// automatic window without the shortest part of its pre-asymptotic head that leaves a constant
// (the head bounds what may be left out: a slow decay is not cut to its last points).
std::optional<ConstantSeries> find_constant(std::span<const double> x, std::span<const double> n,
                                            std::span<const double> y,
                                            const std::vector<bool>& usable,
                                            const FitWindow& set_window,
                                            std::span<const double> floors, double constant_within,
                                            const AsymptoticWindow& power_law_window) {
  std::vector<std::size_t> levels;
  for (std::size_t i = 0; i < y.size(); ++i)
    if (usable[i] && std::isfinite(y[i]) && std::isfinite(n[i]) &&
        (set_window.empty() || inside(set_window, n[i], x[i])))
      levels.push_back(i);
  keep_last(set_window, levels);
  auto constant = detect_constant(y, floors, levels, constant_within);
  const auto& head = power_law_window.head;
  for (std::size_t cut = 1; !constant && set_window.empty() && cut <= head.size(); ++cut) {
    std::vector<std::size_t> rest(head.begin() + static_cast<std::ptrdiff_t>(cut), head.end());
    rest.insert(rest.end(), power_law_window.points.begin(), power_law_window.points.end());
    constant = detect_constant(y, floors, rest, constant_within);
    if (constant)
      constant->head.assign(head.begin(), head.begin() + static_cast<std::ptrdiff_t>(cut));
  }
  return constant;
}

}  // namespace

SeriesAnalysis analyse_series(std::span<const double> x, std::span<const double> n,
                              std::span<const double> y, const std::vector<bool>& usable,
                              double confidence, const FitWindow& set_window,
                              std::span<const double> floors, double constant_within) {
  if (x.size() != y.size() || n.size() != y.size() || usable.size() != y.size())
    throw std::invalid_argument("analyse_series: x, n, y and usable differ in size");
  if (!(confidence > 0.0 && confidence < 1.0))
    throw std::invalid_argument("analyse_series: confidence must lie in (0, 1)");

  const FittedPoints points = fitted_points(x, n, y, usable, set_window, floors);
  SeriesAnalysis out;
  out.evidence = not_a_number;
  out.set_window = set_window.text();
  out.power_law = analyse_model(RateModel::power_law, points, set_window, confidence);
  out.exponential = analyse_model(RateModel::exponential, points, set_window, confidence);
  compare_models(points, out);

  // A bend: the window with its head, else the window alone (a head that is not part of the
  // bend, e.g. a first point before the kernel's support covers the centres).
  const auto& positions = points.positions;
  if (set_window.empty() && positions.size() >= 2) {
    const bool upward = x[positions.back()] > x[positions.front()];
    const auto& window = out.power_law.window;
    std::vector<std::size_t> with_head = window.head;
    with_head.insert(with_head.end(), window.points.begin(), window.points.end());
    if (!try_bend(points, with_head, upward, confidence, out) && !window.head.empty())
      try_bend(points, window.points, upward, confidence, out);
  }

  out.constant =
      find_constant(x, n, y, usable, set_window, floors, constant_within, out.power_law.window);
  return out;
}

}  // namespace rkhs
