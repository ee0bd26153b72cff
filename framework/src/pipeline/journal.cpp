#include "rkhs/pipeline/journal.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "rkhs/report/output.hpp"

namespace rkhs::pipeline {

Journal::Journal(const std::filesystem::path& file, const StudyDefinition& study)
    : study_(study), file_(file) {
  out_.open(file, std::ios::trunc);
  if (!out_)
    throw std::runtime_error(
        fmt::format("cannot write the journal {}: {}", file.string(), std::strerror(errno)));
  out_ << "index,key,status,reason";
  for (const auto& metric : study.metrics) out_ << "," << metric;
  out_ << "\n" << std::flush;
  if (!out_) throw std::runtime_error(fmt::format("cannot write the journal {}", file.string()));
}

void Journal::record(const TrialSpec& trial, const TrialResult& result) {
  out_ << trial.index << "," << csv_field(trial.key) << "," << (result.ok ? "ok" : "failed") << ","
       << csv_field(result.reason);
  for (const auto& metric : study_.metrics)
    out_ << "," << csv_number(result.metrics[study_.metric_index(metric)]);
  out_ << "\n" << std::flush;
  if (!out_) failed_ = true;
}

void Journal::remove() {
  out_.close();
  std::filesystem::remove(file_);
}

}  // namespace rkhs::pipeline
