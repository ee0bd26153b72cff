// The plots of adaptive studies: work precision against a reference integrator, and per group
// the estimates against the road and |x - xhat| and V against time (rkhs/report/plots.cpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <variant>

#include "plot_parts.hpp"
#include "rkhs/core/printable.hpp"

namespace rkhs::plot_detail {

namespace {

// The tolerances a line of a work-precision plot runs through (the integrator's other
// parameters make other lines).
bool is_tolerance(std::string_view parameter) {
  return parameter == "rtol" || parameter == "atol" || parameter == "step";
}

// Where a point lies along its line: the relative tolerance (or rk4's step), loosest first.
double looseness(const PluginChoice& integrator) {
  for (const char* name : {"rtol", "step"})
    for (const auto& [parameter, value] : integrator.parameters.values())
      if (parameter == name) {
        if (const auto* real = std::get_if<double>(&value)) return *real;
        if (const auto* integer = std::get_if<std::int64_t>(&value))
          return static_cast<double>(*integer);
      }
  return 0;
}

// The integrator without its tolerances: one line of a work-precision plot.
std::string line_key(const PluginChoice& integrator) {
  std::string out = integrator.name;
  for (const auto& [parameter, value] : integrator.parameters.values())
    if (!is_tolerance(parameter) && integrator.parameters.given(parameter))
      out += " " + parameter + "=" + format_value(value);
  return out;
}

}  // namespace

// Work-precision plots (DiffEqDevTools' WorkPrecisionSet) of a study with a reference
// integrator: per panel (every axis but the integrator and its tolerances, n included), the
// integration_error of each trial against its wall time and against its steps, one line per
// integrator, its points ordered from the loosest tolerance to the tightest.
void work_precision_scripts(const RunRecord& run, PlotPlan& plan) {
  const auto error_index = run.study.metric_index("integration_error");
  const auto steps_index = run.study.metric_index("steps");
  std::vector<std::string> panels;
  std::map<std::string, std::vector<std::size_t>> members;  // panel -> trials
  for (const auto& trial : run.trials) {
    const auto& own = trial.adaptive_axes();
    std::string panel = fmt::format("kernel={} | target={} | centres={} | plant={} | law={}",
                                    trial.kernel.label(), trial.target.label(),
                                    trial.centres.label(), own.plant.label(), own.law.label());
    if (own.laps) panel += " | laps=" + laps_text(*own.laps);
    panel += fmt::format(" | n={}", trial.n);
    if (!members.contains(panel)) panels.push_back(panel);
    members[panel].push_back(trial.index);
  }
  for (std::size_t p = 0; p < panels.size(); ++p) {
    // Lines in the order their integrators first appear; points by decreasing tolerance.
    std::vector<std::string> lines;
    std::map<std::string, std::vector<std::size_t>> points;
    Extent seconds, steps, errors;
    for (auto index : members[panels[p]]) {
      const auto& result = run.results[index];
      if (!result.ok || !usable_on_log_axis(result.metrics[error_index]) ||
          !usable_on_log_axis(result.seconds))
        continue;
      const auto key = line_key(run.trials[index].adaptive_axes().integrator);
      if (!points.contains(key)) lines.push_back(key);
      points[key].push_back(index);
      seconds.add(result.seconds);
      if (usable_on_log_axis(result.metrics[steps_index])) steps.add(result.metrics[steps_index]);
      errors.add(result.metrics[error_index]);
    }
    const auto& first = run.trials[members[panels[p]].front()];
    const auto& first_own = first.adaptive_axes();
    const auto time_stem = fmt::format("work_precision_time_panel{}", p + 1);
    const auto steps_stem = fmt::format("work_precision_steps_panel{}", p + 1);
    if (lines.empty()) {
      for (const auto& stem : {time_stem, steps_stem})
        plan.notes.push_back(fmt::format(
            "{}: not plotted: no trial of panel {} ({}) has a finite positive integration_error",
            stem, p + 1, panels[p]));
      continue;
    }
    std::string data, plot_time, plot_steps;
    for (std::size_t l = 0; l < lines.size(); ++l) {
      auto& indices = points[lines[l]];
      std::stable_sort(indices.begin(), indices.end(), [&](std::size_t a, std::size_t b) {
        return looseness(run.trials[a].adaptive_axes().integrator) >
               looseness(run.trials[b].adaptive_axes().integrator);
      });
      // seconds, steps, integration_error, tolerance
      data += fmt::format("$line{} << EOD\n", l);
      for (auto index : indices)
        data += fmt::format("{} {} {} {}\n", format_real(run.results[index].seconds),
                            format_real(run.results[index].metrics[steps_index]),
                            format_real(run.results[index].metrics[error_index]),
                            format_real(looseness(run.trials[index].adaptive_axes().integrator)));
      data += "EOD\n";
      const auto title = gp_text(lines[l]);
      for (const auto& [plot, column] : {std::pair<std::string*, int>{&plot_time, 1},
                                         std::pair<std::string*, int>{&plot_steps, 2}})
        *plot += fmt::format(
            "{}$line{} using {}:3 with linespoints pt 7 lc {} title {}, $line{} using {}:3:(sprintf"
            "('%g', $4)) with labels offset char 0.6,0.6 font ',8' tc lt {} notitle",
            plot->empty() ? "" : ", ", l, column, l + 1, title, l, column, l + 1);
    }
    const auto where =
        fmt::format("{}, {}, n = {}{}", first.kernel.label(), first_own.law.name, first.n,
                    first_own.laps ? ", laps=" + laps_text(*first_own.laps) : "");
    const auto& reference = run.study.adaptive_axes().reference;
    std::string tolerances;
    for (const auto& [parameter, value] : reference.parameters.values())
      if (is_tolerance(parameter)) tolerances += " " + parameter + "=" + format_value(value);
    const auto title =
        fmt::format("work precision: {}; reference {}{}", where, reference.name, tolerances);
    const std::string ylabel = "integration error (relative L2 of fhat(T))";
    plan.scripts.emplace_back(
        time_stem,
        rendered(time_stem, sized(run.study.plot, single_figure), run.study.plot, data,
                 line_types() +
                     header(title,
                            fmt::format("wall time of the trial, s (not deterministic: machine, "
                                        "load, {} threads); labels: rtol",
                                        run.threads),
                            ylabel, true, true) +
                     log_range("x", seconds, true) + log_range("y", errors, false) +
                     "set key outside below\nplot " + plot_time + "\n"));
    plan.scripts.emplace_back(
        steps_stem,
        rendered(steps_stem, sized(run.study.plot, single_figure), run.study.plot, data,
                 line_types() + header(title, "accepted steps; labels: rtol", ylabel, true, true) +
                     log_range("x", steps, true) + log_range("y", errors, false) +
                     "set key outside below\nplot " + plot_steps + "\n"));
  }
}

// Per group: the estimates at each snapshot lap (largest n of the group) against the road,
// and |x - xhat| and V against time for every n. Titled by what sets the group apart.
void time_series_scripts(const RunRecord& run, PlotPlan& plan) {
  auto& out = plan.scripts;
  std::map<std::string, std::vector<std::size_t>> groups;
  std::vector<std::string> order;
  for (const auto& trial : run.trials) {
    if (!groups.contains(trial.group_key)) order.push_back(trial.group_key);
    groups[trial.group_key].push_back(trial.index);
  }
  std::vector<const TrialSpec*> firsts;
  for (const auto& key : order) firsts.push_back(&run.trials[groups[key].front()]);
  const auto identity = identify(firsts);
  const auto grid =
      run.study.domain.uniform_points(run.study.adaptive_axes().settings.snapshot_points);
  for (std::size_t g = 0; g < order.size(); ++g) {
    const auto& members = groups[order[g]];
    const auto& last = run.results[members.back()];
    const auto& trial = run.trials[members.back()];
    std::vector<std::size_t> every(identity.factors.size());
    for (std::size_t f = 0; f < every.size(); ++f) every[f] = f;
    const auto name = identity_text(identity, g, every);
    const auto group_name = name.empty() ? legend(trial) : wrapped({name}, 100);
    if (last.ok && !last.snapshots.empty()) {
      std::string data = "$estimates << EOD\n";
      for (std::size_t m = 0; m < grid.size() && m < last.road.size(); ++m) {
        data += fmt::format("{} {}", format_real(grid[m]), format_real(last.road[m]));
        for (const auto& snapshot : last.snapshots)
          data += fmt::format(" {}", format_real(snapshot.estimate[m]));
        data += '\n';
      }
      data += "EOD\n";
      std::string plot = "$estimates using 1:2 with lines lw 2 lc 'black' title 'road f'";
      for (std::size_t i = 0; i < last.snapshots.size(); ++i)
        plot += fmt::format(
            ", $estimates using 1:{} with lines title {}", i + 3,
            gp_text(fmt::format("fhat after {} laps", format_real(last.snapshots[i].lap))));
      const auto stem = fmt::format("estimates_group{}", g + 1);
      out.emplace_back(
          stem, rendered(stem, sized(run.study.plot, single_figure), run.study.plot, data,
                         header(fmt::format("{} (n = {})", group_name, trial.n), "arc length s (m)",
                                "elevation (m)", false, false) +
                             "set autoscale xfix\nset key outside below\nplot " + plot + "\n"));
    } else if (!run.study.adaptive_axes().settings.snapshot_laps.empty()) {
      plan.notes.push_back(
          fmt::format("estimates_group{}: not plotted: the trial with the largest n of group {} {}",
                      g + 1, g + 1, last.ok ? "has no snapshot" : "failed"));
    }
    // |x - xhat| and V on log axes: only trials with a sample the axis can show.
    std::string data, plot_error, plot_v;
    Extent errors, lyapunov;
    for (std::size_t k = 0; k < members.size(); ++k) {
      const auto& result = run.results[members[k]];
      for (const auto& s : result.samples) {
        if (usable_on_log_axis(s.state_error)) errors.add(s.state_error);
        if (usable_on_log_axis(s.lyapunov)) lyapunov.add(s.lyapunov);
      }
      const auto shows = [&](auto value) {
        return std::any_of(result.samples.begin(), result.samples.end(),
                           [&](const TimeSample& s) { return usable_on_log_axis(value(s)); });
      };
      const auto title = gp_text(fmt::format("n = {}", run.trials[members[k]].n));
      if (shows([](const TimeSample& s) { return s.state_error; }))
        plot_error += fmt::format("{}$series{} using 1:2 with lines title {}",
                                  plot_error.empty() ? "" : ", ", k, title);
      if (shows([](const TimeSample& s) { return s.lyapunov; }))
        plot_v += fmt::format("{}$series{} using 1:3 with lines title {}",
                              plot_v.empty() ? "" : ", ", k, title);
      data += fmt::format("$series{} << EOD\n", k);
      for (const auto& s : result.samples)
        data += fmt::format("{} {} {}\n", format_real(s.t),
                            format_real(s.state_error > 0 ? s.state_error : NAN),
                            format_real(s.lyapunov > 0 ? s.lyapunov : NAN));
      data += "EOD\n";
    }
    const auto state_stem = fmt::format("state_error_group{}", g + 1);
    if (!plot_error.empty())
      out.emplace_back(
          state_stem,
          rendered(state_stem, sized(run.study.plot, single_figure), run.study.plot, data,
                   header(group_name + ": |x - xhat|", "t (s)", "|x - xhat|", false, true) +
                       "set autoscale xfix\n" + log_range("y", errors, false) +
                       "set key outside right top\nplot " + plot_error + "\n"));
    else
      plan.notes.push_back(
          fmt::format("{}: not plotted: no trial of group {} has a positive |x - xhat| sample",
                      state_stem, g + 1));
    const auto lyapunov_stem = fmt::format("lyapunov_group{}", g + 1);
    if (!plot_v.empty())
      out.emplace_back(
          lyapunov_stem,
          rendered(lyapunov_stem, sized(run.study.plot, single_figure), run.study.plot, data,
                   header(group_name + ": V", "t (s)", "V", false, true) + "set autoscale xfix\n" +
                       log_range("y", lyapunov, false) + "set key outside right top\nplot " +
                       plot_v + "\n"));
    else
      plan.notes.push_back(fmt::format(
          "{}: not plotted: no trial of group {} has a positive V sample", lyapunov_stem, g + 1));
  }
}

}  // namespace rkhs::plot_detail
