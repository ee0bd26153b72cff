#include "rkhs/report/run_folder.hpp"

#include <fmt/format.h>

#include <exception>
#include <stdexcept>

#include "rkhs/report/html_report.hpp"

namespace rkhs {

void write_run_folder(const RunRecord& record, const std::filesystem::path& directory,
                      bool with_plots, const std::function<void()>& after_outputs) {
  // INCOMPLETE first, removed after the last file: a write that fails part-way leaves it.
  mark_outputs_incomplete(record, directory, output_file_names(record, true, with_plots));
  try {
    write_outputs(record, directory);
    if (after_outputs) after_outputs();
    // Without plots this run, the page embeds none (not those an earlier run left in plots/).
    write_file_atomically(
        directory / "report.html",
        html_report(record, with_plots ? directory / "plots" : std::filesystem::path(),
                    record.verdicts));
  } catch (const std::exception& e) {
    throw std::runtime_error(fmt::format(
        "{}; the outputs in {} may now be partly this run's and partly an earlier run's: {} "
        "says so and lists them",
        e.what(), directory.string(), (directory / incomplete_marker).string()));
  }
  mark_outputs_complete(directory);
}

}  // namespace rkhs
