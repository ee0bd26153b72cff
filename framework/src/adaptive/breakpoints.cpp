// The times an adaptive trial's integration lands on (rkhs/adaptive/breakpoints.hpp), and the
// engine that advances it (adaptive_engine_for): what a trial's horizon asks of time stepping
// and of the lap map.
#include "rkhs/adaptive/breakpoints.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "rkhs/core/cancellation.hpp"

namespace rkhs {

namespace {

bool whole(double laps) {
  return laps >= 1 && laps == std::floor(laps) && laps < 9.2e18;
}

}  // namespace

std::vector<double> path_kink_times(const AdaptiveSettings& settings, const Domain& domain,
                                    const std::vector<double>& kinks) {
  std::vector<double> out;
  const double v = settings.speed;
  if (!settings.shuttle()) {
    for (double kink : kinks) out.push_back(kink / v);
  } else {
    // Out at (k - from) / v and back at (2l - (k - from)) / v; the turning point l / v, where
    // s'(t) jumps, is one too (t = 0 starts every lap anyway).
    const double from = settings.shuttle_from, l = settings.shuttle_length;
    out.push_back(l / v);
    for (double kink : kinks) {
      for (double shift : {0.0, domain.length, -domain.length}) {  // a periodic track's images
        const double u = kink + shift - from;
        if (u > 0 && u < l) {
          out.push_back(u / v);
          out.push_back((2 * l - u) / v);
        }
      }
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<Breakpoint> adaptive_breakpoints(const AdaptiveSettings& settings, const Domain& domain,
                                             double start, double end,
                                             const std::vector<double>& kinks,
                                             bool restart_at_kinks, bool snapshots) {
  std::vector<Breakpoint> points{{start, sample_role, 0}};
  const double lap_time = settings.lap_time(domain.length);
  const double laps_total = (end - start) / lap_time;
  const double sample_count =
      std::max(1.0, std::ceil(laps_total * static_cast<double>(settings.samples_per_lap)));
  const auto in_lap =
      restart_at_kinks ? path_kink_times(settings, domain, kinks) : std::vector<double>{};
  const double kink_count = std::ceil(laps_total) * static_cast<double>(in_lap.size());
  if (!(sample_count + kink_count <= static_cast<double>(max_breakpoints)))
    throw std::length_error(fmt::format(
        "{:.6g} laps stepped through time need {:.3g} breakpoints ({} output samples per lap{}), "
        "more than the {} the time-stepping engine holds; the lap map, whose cost does not "
        "grow with the horizon, takes a whole number of laps below 9.2e18 or laps = \"limit\" "
        "(without final_time)",
        laps_total, sample_count + kink_count, settings.samples_per_lap,
        in_lap.empty() ? "" : fmt::format(" and {} kinks", in_lap.size()), max_breakpoints));
  const auto samples = static_cast<std::size_t>(sample_count);
  for (std::size_t k = 1; k <= samples; ++k) {
    if (k % 65536 == 0) check_cancelled();
    points.push_back({start + (end - start) * static_cast<double>(k) / static_cast<double>(samples),
                      sample_role, 0});
  }
  if (snapshots)
    for (std::size_t i = 0; i < settings.snapshot_laps.size(); ++i) {
      const double t = settings.snapshot_laps[i] * lap_time;
      if (t <= end * (1 + 1e-12)) points.push_back({std::min(t, end), snapshot_role, i});
    }
  if (restart_at_kinks) {
    for (double lap = std::floor(start / lap_time); lap * lap_time < end; ++lap)
      for (double kink_time : in_lap) {
        const double t = lap * lap_time + kink_time;
        if (t > start && t < end) points.push_back({t, 0, 0});
      }
  }
  std::sort(points.begin(), points.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
  std::vector<Breakpoint> merged;
  const double tolerance = 1e-12 * end;
  for (const auto& p : points) {
    if (!merged.empty() && p.t - merged.back().t <= tolerance) {
      merged.back().roles |= p.roles;
      if (p.roles & snapshot_role) merged.back().snapshot_index = p.snapshot_index;
    } else {
      merged.push_back(p);
    }
  }
  return merged;
}

AdaptiveEngine adaptive_engine_for(const AdaptiveSettings& settings, Eigen::Index dimension) {
  const bool applies = settings.final_time <= 0 && (settings.limit() || whole(settings.laps)) &&
                       std::all_of(settings.snapshot_laps.begin(), settings.snapshot_laps.end(),
                                   [](double lap) { return whole(lap); });
  switch (settings.engine) {
    case AdaptiveEngine::time_stepping:
      if (settings.limit())
        throw std::invalid_argument(
            "laps = \"limit\" needs the lap map (engine = \"time_stepping\")");
      return AdaptiveEngine::time_stepping;
    case AdaptiveEngine::lap_map:
      if (!applies)
        throw std::invalid_argument(
            "the lap map needs a whole number of laps (or \"limit\"), no final_time and whole "
            "snapshot laps");
      return AdaptiveEngine::lap_map;
    case AdaptiveEngine::automatic:
      break;
  }
  if (settings.limit() && !applies)
    throw std::invalid_argument(
        "laps = \"limit\" needs the lap map: no final_time and whole snapshot laps");
  return applies && (settings.limit() || settings.laps > static_cast<double>(dimension + 1))
             ? AdaptiveEngine::lap_map
             : AdaptiveEngine::time_stepping;
}

std::string_view adaptive_engine_name(AdaptiveEngine engine) noexcept {
  switch (engine) {
    case AdaptiveEngine::lap_map:
      return "lap_map";
    case AdaptiveEngine::time_stepping:
      return "time_stepping";
    case AdaptiveEngine::automatic:
      return "automatic";
  }
  return "unknown";
}

std::optional<AdaptiveEngine> adaptive_engine_from_name(std::string_view name) noexcept {
  for (const auto engine :
       {AdaptiveEngine::automatic, AdaptiveEngine::lap_map, AdaptiveEngine::time_stepping})
    if (adaptive_engine_name(engine) == name) return engine;
  return std::nullopt;
}

}  // namespace rkhs
