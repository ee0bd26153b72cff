#include "rkhs/report/plots.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <variant>

#include "plot_parts.hpp"
#include "rkhs/core/printable.hpp"

namespace rkhs {

std::vector<std::string> convergence_plot_order(const std::vector<std::string>& metrics) {
  auto rank = [](const std::string& metric) {
    if (metric.find("error") != std::string::npos) return 0;
    if (metric == "fill_distance" || metric == "separation_distance") return 2;
    return 1;
  };
  auto out = metrics;
  std::stable_sort(out.begin(), out.end(),
                   [&](const std::string& a, const std::string& b) { return rank(a) < rank(b); });
  return out;
}

std::vector<std::string> plotted_metrics(const StudyDefinition& study) {
  return study.plot.metrics.empty() ? convergence_plot_order(study.metrics) : study.plot.metrics;
}

PlotPlan plot_scripts(const RunRecord& run) {
  PlotPlan plan;
  for (const auto& metric : plotted_metrics(run.study))
    plot_detail::convergence_scripts(run, metric, plan);
  if (!run.study.kind_descriptor().outputs().time_series_plots) return plan;
  // The kind with time-series plots has the adaptive axes.
  if (!run.study.adaptive_axes().reference.name.empty())
    plot_detail::work_precision_scripts(run, plan);
  plot_detail::time_series_scripts(run, plan);
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

// The file gnuplot is run from: the first executable `gnuplot` on PATH, or nothing.
std::optional<std::filesystem::path> find_gnuplot() {
  const char* path = std::getenv("PATH");
  std::string_view rest = path && *path ? path : "/usr/local/bin:/usr/bin:/bin";
  while (true) {
    const auto colon = rest.find(':');
    const std::string directory(rest.substr(0, colon));
    const auto candidate = std::filesystem::path(directory.empty() ? "." : directory) / "gnuplot";
    if (::access(candidate.c_str(), X_OK) == 0 && !std::filesystem::is_directory(candidate))
      return candidate;
    if (colon == std::string_view::npos) return std::nullopt;
    rest.remove_prefix(colon + 1);
  }
}

// How a gnuplot process ended.
enum class GnuplotEnd { success, failed, timed_out, stopped };

// Runs `gnuplot <script>` in `folder` with its standard error to `log` (standard input and
// output /dev/null), directly (fork and exec: no shell sees a name), in a process group of its
// own. Polls it every 20 ms: past `options.gnuplot_seconds`, or once options.stop_requested
// returns true, the whole group is killed (gnuplot and anything it started).
GnuplotEnd run_gnuplot(const std::filesystem::path& gnuplot, const std::filesystem::path& folder,
                       const std::string& script, const std::string& log,
                       const PlotOptions& options) {
  const std::string program = gnuplot.string();
  const pid_t child = ::fork();
  if (child < 0) return GnuplotEnd::failed;
  if (child == 0) {
    // Only async-signal-safe calls from here on.
    ::setpgid(0, 0);
    if (::chdir(folder.c_str()) != 0) ::_exit(127);
    const int null = ::open("/dev/null", O_RDWR);
    const int err = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (null < 0 || err < 0) ::_exit(127);
    ::dup2(null, STDIN_FILENO);
    ::dup2(null, STDOUT_FILENO);
    ::dup2(err, STDERR_FILENO);
    char* const argv[] = {const_cast<char*>("gnuplot"), const_cast<char*>(script.c_str()), nullptr};
    ::execv(program.c_str(), argv);
    ::_exit(127);
  }
  ::setpgid(child, child);  // as the child does: whichever runs first, the group exists
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(std::min(options.gnuplot_seconds, 1e9)));
  int status = 0;
  while (true) {
    const pid_t done = ::waitpid(child, &status, WNOHANG);
    if (done == child) break;
    if (done < 0 && errno != EINTR) return GnuplotEnd::failed;
    const bool stop = options.stop_requested && options.stop_requested();
    if (stop || std::chrono::steady_clock::now() >= deadline) {
      ::kill(-child, SIGKILL);
      ::kill(child, SIGKILL);  // should it not have reached setpgid yet
      while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
      }
      return stop ? GnuplotEnd::stopped : GnuplotEnd::timed_out;
    }
    ::usleep(20'000);  // a signal (SIGTERM) ends the sleep early
  }
  return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? GnuplotEnd::success : GnuplotEnd::failed;
}

constexpr const char* plot_extensions[] = {".svg", ".png", ".pdf"};
constexpr const char* manifest_name = ".rkhs-study-manifest";
constexpr std::string_view manifest_heading =
    "# rkhs-study: the files a run wrote in this folder; the next run removes these (and only "
    "these) before it writes its own\n";

// The names the manifest in `folder` lists: plain file names in the folder, no paths (a line
// that is not one is ignored).
std::vector<std::string> manifest_entries(const std::filesystem::path& folder) {
  std::ifstream in(folder / manifest_name);
  std::vector<std::string> names;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line.front() == '#' || line == "." || line == ".." ||
        line.find('/') != std::string::npos || line.find('\0') != std::string::npos ||
        line == manifest_name)
      continue;
    names.push_back(line);
  }
  return names;
}
}  // namespace

PlotOptions plot_options(std::function<bool()> stop_requested) {
  PlotOptions options;
  options.stop_requested = std::move(stop_requested);
  if (const char* text = std::getenv("RKHS_STUDY_GNUPLOT_SECONDS"); text && *text) {
    char* end = nullptr;
    const double seconds = std::strtod(text, &end);
    if (end && *end == '\0' && std::isfinite(seconds) && seconds > 0)
      options.gnuplot_seconds = seconds;
  }
  return options;
}

PlotOutcome write_plots(const RunRecord& run, const std::filesystem::path& directory,
                        const PlotOptions& options) {
  const auto folder = directory / "plots";
  std::filesystem::create_directories(folder);
  // The folder shows this run only: plots of an earlier run into the same directory (a metric
  // no longer plotted, a plot that fails now) must not be taken for this one's. Only the files
  // an earlier run listed in the manifest are removed: a file of the user's own stays.
  for (const auto& name : manifest_entries(folder)) {
    std::error_code error;
    const auto file = folder / name;
    if (std::filesystem::is_regular_file(std::filesystem::symlink_status(file, error)))
      std::filesystem::remove(file, error);
  }
  auto plan = plot_scripts(run);
  PlotOutcome outcome;
  outcome.notes = std::move(plan.notes);
  // Every file this run may write, listed before it writes any (a run that stops part-way
  // leaves a manifest that still names them).
  std::string manifest(manifest_heading);
  for (const auto& [stem, script] : plan.scripts)
    for (const char* extension : {".gp", ".svg", ".png", ".pdf", ".log"})
      manifest += stem + extension + "\n";
  write_file_atomically(folder / manifest_name, manifest);
  if (plan.scripts.empty()) return outcome;
  const auto gnuplot = find_gnuplot();
  if (!gnuplot) {
    outcome.failures.push_back(
        "gnuplot is not installed (not found on PATH): no plot was rendered (Debian: apt-get "
        "install gnuplot-nox; or run with --no-plots)");
    return outcome;
  }
  for (const auto& [stem, script] : plan.scripts) {
    const auto gp = folder / (stem + ".gp");
    const auto log = folder / (stem + ".log");
    try {
      write_file_atomically(gp, "# " + stem + ": run gnuplot " + stem +
                                    ".gp in this folder (writes " + stem +
                                    ".svg, .png and .pdf)\n" + script);
    } catch (const std::exception& e) {  // a full disk: this plot is not rendered
      outcome.failures.push_back(e.what());
      continue;
    }
    // In the plots folder: the script names its outputs without a path, so it is the same
    // wherever the run wrote it.
    const auto end = run_gnuplot(*gnuplot, folder, stem + ".gp", stem + ".log", options);
    if (end != GnuplotEnd::success) {
      outcome.failures.push_back(
          end == GnuplotEnd::timed_out
              ? fmt::format("{}: gnuplot did not finish within {} s and was killed", gp.string(),
                            options.gnuplot_seconds)
          : end == GnuplotEnd::stopped
              ? fmt::format("{}: gnuplot was killed: the command was interrupted", gp.string())
              : fmt::format("{}: {}", gp.string(), gnuplot_message(log)));
      for (const char* extension : plot_extensions)  // half-written images are not plots
        std::filesystem::remove(folder / (stem + extension));
      if (end == GnuplotEnd::stopped) {
        outcome.interrupted = true;
        break;
      }
      continue;
    }
    std::filesystem::remove(log);
    outcome.rendered.push_back(stem);
  }
  return outcome;
}

}  // namespace rkhs
