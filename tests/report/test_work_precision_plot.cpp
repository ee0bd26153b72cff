// Work-precision plots of a study with a reference integrator: per panel (every axis but the
// integrator and its tolerances), integration_error against wall time and against steps, one
// line per integrator with its points ordered by rtol. The results are made up, so no trial
// runs here; gnuplot renders them when it is installed (ci/setup installs it).
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "rkhs/report/html_report.hpp"
#include "rkhs/report/output.hpp"
#include "rkhs/report/plots.hpp"

using namespace rkhs;

namespace {

StudyDefinition work_precision_study(bool with_reference) {
  return parse_study(std::string(R"([study]
name = "wp"
kind = "adaptive"
evaluation_points = 64
metrics = ["integration_error", "steps"]
[domain]
radius = 1.0
[grid]
n = [4, 8]
[[kernel]]
name = "gaussian"
[[plant]]
name = "linear"
A = "-1"
B = "1"
[[integrator]]
name = "radau5"
rtol = [1e-4, 1e-3, 1e-5]
[[integrator]]
name = "rodas4"
rtol = [1e-3, 1e-4]
[adaptive]
speed = 0.5
laps = 1
)") + (with_reference ? "reference = { integrator = \"radau5\", rtol = 1e-11, atol = 1e-10 }\n"
                      : ""),
                     "wp.toml");
}

// integration_error = rtol (x 2 for n = 8), steps = 1 / rtol, seconds = 1e-3 / rtol (x 3 for
// rodas4); radau5 at rtol 1e-5 and n = 8 failed.
std::vector<TrialResult> made_up_results(const StudyDefinition& study,
                                         const std::vector<TrialSpec>& trials) {
  std::vector<TrialResult> results;
  for (const auto& trial : trials) {
    TrialResult result;
    const auto& integrator = trial.adaptive_axes().integrator;
    const double rtol = integrator.parameters.real("rtol");
    result.ok = !(integrator.name == "radau5" && rtol == 1e-5 && trial.n == 8);
    result.metrics.assign(study.all_metrics().size(), std::numeric_limits<double>::quiet_NaN());
    if (result.ok) {
      result.metrics[study.metric_index("integration_error")] = rtol * (trial.n == 8 ? 2 : 1);
      result.metrics[study.metric_index("steps")] = std::round(1 / rtol);
    } else {
      result.reason = "made up";
    }
    result.seconds = 1e-3 / rtol * (integrator.name == "rodas4" ? 3 : 1);
    results.push_back(std::move(result));
  }
  return results;
}

const std::string* script_of(const PlotPlan& plan, const std::string& stem) {
  for (const auto& [name, script] : plan.scripts)
    if (name == stem) return &script;
  return nullptr;
}

}  // namespace

TEST_CASE(
    "work-precision plots: one panel per group without the integrator, a line per "
    "integrator ordered by rtol",
    "[report][plots][work_precision]") {
  const auto study = work_precision_study(true);
  const auto trials = study.trials();
  REQUIRE(trials.size() == 10);  // (3 + 2 integrators) x 2 n
  const auto results = made_up_results(study, trials);
  const std::vector<MetricSeries> rates;
  const RunRecord run{study, trials, results, rates, 2, 0.0, "2026-01-01T00:00:00Z"};
  const auto plan = plot_scripts(run);

  const auto* time1 = script_of(plan, "work_precision_time_panel1");
  const auto* steps1 = script_of(plan, "work_precision_steps_panel1");
  const auto* time2 = script_of(plan, "work_precision_time_panel2");
  REQUIRE(time1);
  REQUIRE(steps1);
  REQUIRE(time2);
  CHECK_FALSE(script_of(plan, "work_precision_time_panel3"));  // n = 4 and n = 8 only

  // Panel 1 is n = 4: radau5's points from the loosest rtol to the tightest, whatever the
  // order of the file: seconds, steps, integration_error, rtol.
  CHECK_THAT(*time1, Catch::Contains("$line0 << EOD\n"
                                     "1 1000 0.001 0.001\n"
                                     "10 10000 1e-04 1e-04\n"
                                     "100 1e+05 1e-05 1e-05\n"
                                     "EOD\n"));
  CHECK_THAT(*time1, Catch::Contains("$line1 << EOD\n"
                                     "3 1000 0.001 0.001\n"
                                     "30 10000 1e-04 1e-04\n"
                                     "EOD\n"));
  CHECK_THAT(*time1, Catch::Contains("n = 4"));
  CHECK_THAT(*time1, Catch::Contains("reference radau5 rtol=1e-11 atol=1e-10"));
  CHECK_THAT(*time1, Catch::Contains("set logscale x") && Catch::Contains("set logscale y"));
  CHECK_THAT(*time1, Catch::Contains("$line0 using 1:3 with linespoints pt 7 lc 1 title 'radau5'"));
  CHECK_THAT(*time1, Catch::Contains("$line1 using 1:3 with linespoints pt 7 lc 2 title 'rodas4'"));
  CHECK_THAT(*time1, Catch::Contains("not deterministic"));
  CHECK_THAT(*steps1, Catch::Contains("$line0 using 2:3 with linespoints"));
  CHECK_THAT(*steps1, Catch::Contains("accepted steps"));
  // Panel 2 (n = 8) leaves out the failed trial.
  CHECK_THAT(*time2, Catch::Contains("$line0 << EOD\n"
                                     "1 1000 0.002 0.001\n"
                                     "10 10000 2e-04 1e-04\n"
                                     "EOD\n"));
  CHECK_THAT(*time2, Catch::Contains("n = 8"));

  // No reference: no work-precision plot.
  const auto plain = work_precision_study(false);
  const auto plain_trials = plain.trials();
  const auto plain_results = made_up_results(plain, plain_trials);
  const RunRecord plain_run{plain, plain_trials, plain_results,         rates,
                            2,     0.0,          "2026-01-01T00:00:00Z"};
  for (const auto& [stem, script] : plot_scripts(plain_run).scripts)
    CHECK_FALSE(stem.starts_with("work_precision_"));

  // Rendered by gnuplot (when installed): SVG and non-empty PNG, and in report.html.
  if (std::system("command -v gnuplot > /dev/null 2>&1") != 0) {
    WARN("gnuplot is not installed: the work-precision plots were not rendered");
    return;
  }
  const auto directory = std::filesystem::temp_directory_path() / "rkhs_work_precision_plot";
  std::filesystem::remove_all(directory);
  const auto outcome = write_plots(run, directory);
  INFO((outcome.failures.empty() ? std::string() : outcome.failures.front()));
  CHECK(outcome.failures.empty());
  for (const char* stem : {"work_precision_time_panel1", "work_precision_steps_panel1",
                           "work_precision_time_panel2", "work_precision_steps_panel2"}) {
    INFO(stem);
    const auto png = directory / "plots" / (std::string(stem) + ".png");
    REQUIRE(std::filesystem::exists(png));
    CHECK(std::filesystem::file_size(png) > 1000);
    CHECK(std::filesystem::exists(directory / "plots" / (std::string(stem) + ".svg")));
  }
  const auto page = html_report(run, directory / "plots");
  CHECK_THAT(page, Catch::Contains("<h2 id=\"work-precision\">Work precision</h2>"));
  CHECK_THAT(page, Catch::Contains("Wall time is not deterministic"));
  CHECK_THAT(page, Catch::Contains("alt=\"work_precision_time_panel1.svg\""));
  std::filesystem::remove_all(directory);
}
