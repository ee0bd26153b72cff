#include "rkhs/report/plots.hpp"

#include "rkhs/kernel/kernel.hpp"
#include "rkhs/rates/theory.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <algorithm>
#include <map>
#include <variant>

namespace rkhs {

namespace {

std::string gnuplot_string(std::string_view text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    out += c == '_' ? ' ' : c;  // '_' would start a subscript in gnuplot's enhanced text
  }
  return out + "\"";
}

std::string header(std::string_view title, std::string_view xlabel, std::string_view ylabel,
                   bool logx, bool logy) {
  return fmt::format(
      "set title {}\nset xlabel {}\nset ylabel {}\n{}{}set grid\nset key outside right top "
      "box\nset datafile missing 'nan'\n",
      gnuplot_string(title), gnuplot_string(xlabel), gnuplot_string(ylabel), logx ? "set logscale x\n" : "",
      logy ? "set logscale y\nset format y '10^{%L}'\n" : "");
}

// A value a logarithmic axis can show.
bool usable_on_log_axis(double v) {
  return std::isfinite(v) && v > 0;
}

// Short legend text for a group: the plugin labels without the defaults' noise, and the lap
// count of a laps axis.
std::string legend(const TrialSpec& trial) {
  std::string out = trial.kernel.label();
  for (const auto* choice : {&trial.law, &trial.integrator})
    if (!choice->name.empty()) out += ", " + choice->name;
  if (trial.laps) out += ", laps=" + laps_text(*trial.laps);  // a laps axis: one curve per count
  return out;
}

std::string convergence_script(const RunRecord& run, const std::string& metric) {
  std::string data, plot;
  std::size_t block = 0;
  for (const auto& series : run.rates) {
    if (series.metric != metric || series.trials.empty()) continue;
    if (std::none_of(series.values.begin(), series.values.end(), usable_on_log_axis)) continue;
    const bool in_n = series.analysis.reported == RateModel::exponential || run.study.abscissa == Abscissa::n;
    const auto& x = in_n ? series.n : series.abscissa;
    // Points (flagged ones in a second column), then the fitted line and its confidence band.
    data += fmt::format("$points{} << EOD\n", block);
    for (std::size_t k = 0; k < series.trials.size(); ++k) {
      const double v = series.values[k];
      const bool usable = usable_on_log_axis(v);
      data += fmt::format("{} {} {}\n", format_real(x[k]),
                          usable && !series.flagged[k] ? format_real(v) : "nan",
                          usable && series.flagged[k] ? format_real(v) : "nan");
    }
    data += "EOD\n";
    const auto label = legend(run.trials[series.trials.front()]);
    plot += fmt::format("$points{} using 1:2 with linespoints pt 7 lc {} title {}, ", block,
                        block + 1, gnuplot_string(label));
    if (std::find(series.flagged.begin(), series.flagged.end(), true) != series.flagged.end())
      plot += fmt::format("$points{} using 1:3 with points pt 6 lc {} notitle, ", block, block + 1);
    if (const auto& fit = series.fit; fit && !fit->used.empty()) {
      // The fit in log space pivots about the mean of the fitted points; the band spans the
      // slopes of the confidence interval about the same pivot.
      double mean_u = 0, mean_y = 0;
      for (auto k : fit->used) {
        mean_u += fit->model == RateModel::exponential ? x[k] : std::log(x[k]);
        mean_y += std::log(series.values[k]);
      }
      mean_u /= static_cast<double>(fit->used.size());
      mean_y /= static_cast<double>(fit->used.size());
      data += fmt::format("$fit{} << EOD\n", block);
      const double first = x[fit->used.front()], last = x[fit->used.back()];
      for (int i = 0; i <= 20; ++i) {
        const double t = i / 20.0;
        const double xi = fit->model == RateModel::exponential
                              ? first + t * (last - first)
                              : std::exp(std::log(first) + t * (std::log(last) - std::log(first)));
        const double u = fit->model == RateModel::exponential ? xi : std::log(xi);
        auto at = [&](double slope) { return std::exp(mean_y + slope * (u - mean_u)); };
        const bool band = std::isfinite(fit->ci_low) && std::isfinite(fit->ci_high);
        const double lo = band ? std::min(at(fit->ci_low), at(fit->ci_high)) : at(fit->rate);
        const double hi = band ? std::max(at(fit->ci_low), at(fit->ci_high)) : at(fit->rate);
        data += fmt::format("{} {} {} {}\n", format_real(xi), format_real(at(fit->rate)),
                            format_real(lo), format_real(hi));
      }
      data += "EOD\n";
      plot += fmt::format("$fit{} using 1:3:4 with filledcurves fc lt {} fs transparent solid 0.2 "
                          "notitle, $fit{} using 1:2 with lines dt 2 lc {} title {}, ",
                          block, block + 1, block, block + 1,
                          gnuplot_string(fmt::format("rate {:.3g}{}", fit->rate,
                                             fit->model == RateModel::exponential ? " (exp in n)" : "")));
    }
    // The theory slope (power-law theories from the kernel's metadata), through the first usable
    // point: what the fitted line should be parallel to.
    try {
      const auto& trial = run.trials[series.trials.front()];
      const auto theory = theory_rate(
          metric, kernel_properties(trial.kernel.name, trial.kernel.parameters, run.study.domain));
      std::size_t first = series.trials.size();
      for (std::size_t k = 0; k < series.trials.size(); ++k)
        if (!series.flagged[k] && std::isfinite(series.values[k]) && series.values[k] > 0) {
          first = k;
          break;
        }
      if (theory && theory->model == RateModel::power_law && first < series.trials.size() && in_n == (run.study.abscissa == Abscissa::n)) {
        const double slope =
            run.study.abscissa == Abscissa::n ? -theory->h_exponent / theory->dimension
                                             : theory->h_exponent;
        data += fmt::format("$theory{} << EOD\n", block);
        for (std::size_t k = first; k < series.trials.size(); ++k)
          data += fmt::format("{} {}\n", format_real(x[k]),
                              format_real(series.values[first] * std::pow(x[k] / x[first], slope)));
        data += "EOD\n";
        plot += fmt::format("$theory{} using 1:2 with lines dt 3 lw 2 lc {} title {}, ", block, block + 1,
                            gnuplot_string(fmt::format("theory slope {:.3g}", slope)));
      }
    } catch (const std::exception&) {
      // A kernel that cannot be rebuilt here (e.g. from an unloaded plugin): no theory line.
    }
    ++block;
  }
  if (block == 0) return {};
  plot.erase(plot.size() - 2);
  const bool exponential_axis = run.study.abscissa == Abscissa::n;
  return data + header(metric + " (" + run.study.name + "; hollow: flagged, not fitted)",
                       exponential_axis ? "n" : "fill distance h", metric, true, true) +
         "plot " + plot + "\n";
}

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
    std::string panel = fmt::format("kernel={} | target={} | centres={} | plant={} | law={}",
                                    trial.kernel.label(), trial.target.label(),
                                    trial.centres.label(), trial.plant.label(), trial.law.label());
    if (trial.laps) panel += " | laps=" + laps_text(*trial.laps);
    panel += fmt::format(" | n={}", trial.n);
    if (!members.contains(panel)) panels.push_back(panel);
    members[panel].push_back(trial.index);
  }
  for (std::size_t p = 0; p < panels.size(); ++p) {
    // Lines in the order their integrators first appear; points by decreasing tolerance.
    std::vector<std::string> lines;
    std::map<std::string, std::vector<std::size_t>> points;
    for (auto index : members[panels[p]]) {
      const auto& result = run.results[index];
      if (!result.ok || !usable_on_log_axis(result.metrics[error_index]) ||
          !usable_on_log_axis(result.seconds))
        continue;
      const auto key = line_key(run.trials[index].integrator);
      if (!points.contains(key)) lines.push_back(key);
      points[key].push_back(index);
    }
    const auto& first = run.trials[members[panels[p]].front()];
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
        return looseness(run.trials[a].integrator) > looseness(run.trials[b].integrator);
      });
      // seconds, steps, integration_error, tolerance
      data += fmt::format("$line{} << EOD\n", l);
      for (auto index : indices)
        data += fmt::format("{} {} {} {}\n", format_real(run.results[index].seconds),
                            format_real(run.results[index].metrics[steps_index]),
                            format_real(run.results[index].metrics[error_index]),
                            format_real(looseness(run.trials[index].integrator)));
      data += "EOD\n";
      const auto title = gnuplot_string(lines[l]);
      for (const auto& [plot, column] : {std::pair<std::string*, int>{&plot_time, 1},
                                         std::pair<std::string*, int>{&plot_steps, 2}})
        *plot += fmt::format(
            "{}$line{} using {}:3 with linespoints pt 7 lc {} title {}, $line{} using {}:3:(sprintf"
            "('%g', $4)) with labels offset char 0.6,0.6 font ',8' tc lt {} notitle",
            plot->empty() ? "" : ", ", l, column, l + 1, title, l, column, l + 1);
    }
    const auto where = fmt::format("{}, {}, n = {}{}", first.kernel.label(), first.law.name,
                                   first.n, first.laps ? ", laps=" + laps_text(*first.laps) : "");
    std::string tolerances;
    for (const auto& [parameter, value] : run.study.reference.parameters.values())
      if (is_tolerance(parameter)) tolerances += " " + parameter + "=" + format_value(value);
    const auto title = fmt::format("work precision: {}; reference {}{}", where,
                                   run.study.reference.name, tolerances);
    const std::string ylabel = "integration error (relative L2 of fhat(T))";
    plan.scripts.emplace_back(
        time_stem,
        data +
            header(title,
                   fmt::format("wall time of the trial, s (not deterministic: machine, load, {} "
                               "threads); labels: rtol",
                               run.threads),
                   ylabel, true, true) +
            "set key inside bottom left box\nplot " + plot_time + "\n");
    plan.scripts.emplace_back(
        steps_stem, data + header(title, "accepted steps; labels: rtol", ylabel, true, true) +
                        "set key inside bottom left box\nplot " + plot_steps + "\n");
  }
}

}  // namespace

PlotPlan plot_scripts(const RunRecord& run) {
  PlotPlan plan;
  auto& out = plan.scripts;
  for (const auto& metric : run.study.metrics) {
    if (auto script = convergence_script(run, metric); !script.empty())
      out.emplace_back("convergence_" + metric, std::move(script));
    else
      plan.notes.push_back(fmt::format(
          "convergence_{}: not plotted: no trial has a finite positive {} (a log axis needs one)",
          metric, metric));
  }
  if (run.study.kind != StudyKind::adaptive) return plan;
  if (!run.study.reference.name.empty()) work_precision_scripts(run, plan);

  // Per group: the estimates at each snapshot lap (largest n of the group) against the road,
  // and |x - xhat| and V against time for every n.
  std::map<std::string, std::vector<std::size_t>> groups;
  std::vector<std::string> order;
  for (const auto& trial : run.trials) {
    if (!groups.contains(trial.group_key)) order.push_back(trial.group_key);
    groups[trial.group_key].push_back(trial.index);
  }
  const auto grid = run.study.domain.uniform_points(run.study.adaptive.snapshot_points);
  for (std::size_t g = 0; g < order.size(); ++g) {
    const auto& members = groups[order[g]];
    const auto& last = run.results[members.back()];
    const auto& trial = run.trials[members.back()];
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
        plot += fmt::format(", $estimates using 1:{} with lines title {}", i + 3,
                            gnuplot_string(fmt::format("fhat after {} laps", format_real(last.snapshots[i].lap))));
      out.emplace_back(fmt::format("estimates_group{}", g + 1),
                       data + header(fmt::format("{} (n = {})", legend(trial), trial.n),
                                     "arc length s (m)", "elevation (m)", false, false) +
                           "plot " + plot + "\n");
    } else if (!run.study.adaptive.snapshot_laps.empty()) {
      plan.notes.push_back(fmt::format(
          "estimates_group{}: not plotted: the trial with the largest n of group {} {}", g + 1,
          g + 1, last.ok ? "has no snapshot" : "failed"));
    }
    // |x - xhat| and V on log axes: only trials with a sample the axis can show.
    std::string data, plot_error, plot_v;
    for (std::size_t k = 0; k < members.size(); ++k) {
      const auto& result = run.results[members[k]];
      const auto shows = [&](auto value) {
        return std::any_of(result.samples.begin(), result.samples.end(),
                           [&](const TimeSample& s) { return usable_on_log_axis(value(s)); });
      };
      const auto title = gnuplot_string(fmt::format("n = {}", run.trials[members[k]].n));
      if (shows([](const TimeSample& s) { return s.state_error; }))
        plot_error += fmt::format("{}$series{} using 1:2 with lines title {}",
                                  plot_error.empty() ? "" : ", ", k, title);
      if (shows([](const TimeSample& s) { return s.lyapunov; }))
        plot_v += fmt::format("{}$series{} using 1:3 with lines title {}",
                              plot_v.empty() ? "" : ", ", k, title);
      data += fmt::format("$series{} << EOD\n", k);
      for (const auto& s : result.samples)
        data += fmt::format("{} {} {}\n", format_real(s.t), format_real(s.state_error > 0 ? s.state_error : NAN),
                            format_real(s.lyapunov > 0 ? s.lyapunov : NAN));
      data += "EOD\n";
    }
    const auto state_stem = fmt::format("state_error_group{}", g + 1);
    if (!plot_error.empty())
      out.emplace_back(state_stem, data + header(legend(trial) + ": |x - xhat|", "t (s)",
                                                 "|x - xhat|", false, true) +
                                       "plot " + plot_error + "\n");
    else
      plan.notes.push_back(fmt::format(
          "{}: not plotted: no trial of group {} has a positive |x - xhat| sample", state_stem, g + 1));
    const auto lyapunov_stem = fmt::format("lyapunov_group{}", g + 1);
    if (!plot_v.empty())
      out.emplace_back(lyapunov_stem, data + header(legend(trial) + ": V", "t (s)", "V", false, true) +
                                          "plot " + plot_v + "\n");
    else
      plan.notes.push_back(
          fmt::format("{}: not plotted: no trial of group {} has a positive V sample", lyapunov_stem, g + 1));
  }
  return plan;
}

namespace {
// gnuplot's own complaint from its log: the lines that say what went wrong, joined.
std::string gnuplot_message(const std::filesystem::path& log) {
  std::ifstream in(log);
  std::string line, message;
  while (std::getline(in, line)) {
    if (line.find_first_not_of(" \t^") == std::string::npos) continue;  // blank or the caret line
    if (!message.empty()) message += " ";
    message += line.substr(line.find_first_not_of(" \t"));
  }
  return message.empty() ? "gnuplot exited with an error and said nothing" : message;
}
}  // namespace

PlotOutcome write_plots(const RunRecord& run, const std::filesystem::path& directory) {
  const auto folder = directory / "plots";
  std::filesystem::create_directories(folder);
  // The folder shows this run only: plots of an earlier run into the same directory (a metric
  // no longer plotted, a plot that fails now) must not be taken for this one's.
  for (const auto& entry : std::filesystem::directory_iterator(folder))
    for (const char* extension : {".gp", ".svg", ".png", ".log"})
      if (entry.is_regular_file() && entry.path().extension() == extension)
        std::filesystem::remove(entry.path());
  auto plan = plot_scripts(run);
  PlotOutcome outcome;
  outcome.notes = std::move(plan.notes);
  if (plan.scripts.empty()) return outcome;
  if (std::system("command -v gnuplot > /dev/null 2>&1") != 0) {
    outcome.failures.push_back(
        "gnuplot is not installed (not found on PATH): no plot was rendered (Debian: apt-get "
        "install gnuplot-nox; or run with --no-plots)");
    return outcome;
  }
  for (const auto& [stem, script] : plan.scripts) {
    const auto gp = folder / (stem + ".gp");
    const auto log = folder / (stem + ".log");
    {
      std::ofstream out(gp);
      out << "# " << stem << ": render with gnuplot (writes " << stem << ".svg and .png)\n";
      out << "set terminal svg size 900,560 dynamic enhanced font 'sans,11'\nset output '"
          << (folder / (stem + ".svg")).string() << "'\n"
          << script << "set terminal pngcairo size 900,560 font 'sans,10'\nset output '"
          << (folder / (stem + ".png")).string() << "'\nreplot\n";
    }
    const auto command = fmt::format("gnuplot '{}' 2> '{}'", gp.string(), log.string());
    if (std::system(command.c_str()) != 0) {
      outcome.failures.push_back(fmt::format("{}: {}", gp.string(), gnuplot_message(log)));
      for (const char* extension : {".svg", ".png"})  // half-written images are not plots
        std::filesystem::remove(folder / (stem + extension));
      continue;
    }
    std::filesystem::remove(log);
    outcome.rendered.push_back(stem);
  }
  return outcome;
}

}  // namespace rkhs
