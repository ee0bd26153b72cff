#pragma once
// journal.csv of an output folder (docs/results.md): `run` appends each finished trial here and
// flushes at once, so an interrupted run keeps the metrics of what it computed even without a
// result store (--no-store). The journal is removed once the outputs are complete; one left
// behind marks an output folder whose run did not finish.
//
// Columns: index, key, status (ok or failed), reason, then the study's metrics, in the number
// format of trials.csv.

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "rkhs/run/run.hpp"
#include "rkhs/study/study.hpp"

namespace rkhs::pipeline {

class Journal {
 public:
  /// Creates (truncates) `file` and writes the header for the study's metrics.
  Journal(const std::filesystem::path& file, const StudyDefinition& study);
  /// Appends one finished trial and flushes; a write that fails (a full disk) is remembered,
  /// never thrown (this runs in a trial's callback).
  void record(const TrialSpec& trial, const TrialResult& result);
  /// True while every write succeeded: the file then holds every trial recorded.
  bool complete() const { return !failed_; }
  /// Closes and deletes the journal (the outputs hold everything now).
  void remove();
  const std::filesystem::path& file() const { return file_; }

 private:
  const StudyDefinition& study_;
  std::filesystem::path file_;
  std::ofstream out_;
  bool failed_ = false;
};

}  // namespace rkhs::pipeline
