// `rkhs-study report DIR`: the tables of the run in DIR again, from DIR/summary.json alone
// (read_results_folder). The study file it names is never read, no trial is run, no plugin is
// loaded and no result store is opened: a results folder is data, whoever sent it.
#include <CLI/CLI.hpp>
#include <iostream>
#include <limits>
#include <memory>

#include "commands/commands.hpp"
#include "commands/common.hpp"
#include "rkhs/report/html_report.hpp"
#include "rkhs/report/output.hpp"
#include "rkhs/report/run_summary.hpp"

namespace rkhs::cli {

int command_report(const std::string& directory, const std::string& format) {
  const auto folder = read_results_folder(directory);
  const auto record = folder.record();
  if (format == "text") {
    std::cout << console_tables(record, std::numeric_limits<std::size_t>::max());
  } else if (format == "md") {
    std::cout << markdown_tables(record);
  } else if (format == "tex") {
    std::cout << latex_tables(record);
  } else {
    // The page shows the verdicts the run recorded; nothing is judged again.
    const auto file = std::filesystem::path(directory) / "report.html";
    write_file_atomically(file, html_report(record, std::filesystem::path(directory) / "plots",
                                            folder.judged ? &folder.verdicts : nullptr));
    std::cout << "wrote " << file.string() << "\n";
  }
  return exit_ok;
}

Command add_report_command(CLI::App& app) {
  struct Arguments {
    std::string directory, format = "html";
  };
  auto arguments = std::make_shared<Arguments>();
  auto* report = app.add_subcommand(
      "report",
      "the rate tables of a run again, from the folder's summary.json alone (runs nothing, "
      "loads no plugin, opens no store): text, Markdown, LaTeX or report.html");
  report->add_option("directory", arguments->directory, "a results directory (with summary.json)")
      ->required()
      ->check(CLI::ExistingDirectory);
  report
      ->add_option("--format", arguments->format,
                   "text (the console's tables, every group's), md, tex or html (default html: "
                   "writes DIR/report.html)")
      ->check(CLI::IsMember({"text", "md", "tex", "html"}));
  // A results folder is data: no plugin is loaded for it.
  return {report, [](SessionOptions& options) { options.loads_plugins = false; },
          [arguments](pipeline::Executor&) {
            return command_report(arguments->directory, arguments->format);
          }};
}

}  // namespace rkhs::cli
