#include "rkhs/report/run_summary.hpp"

#include <fmt/format.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace rkhs {

RunSummary read_run_summary(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot open (is it a results directory?)");
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw std::runtime_error(fmt::format("{}: not a summary.json written by rkhs-study: {}",
                                         file.string(), e.what()));
  }
  const auto text = [&](const char* key) -> std::string {
    if (!json.is_object() || !json.contains(key) || !json[key].is_string()) return {};
    return json[key].get<std::string>();
  };
  RunSummary summary{text("study"), text("source"), text("tier")};
  if (summary.source.empty())
    throw std::runtime_error(file.string() + ": no \"source\" study file recorded");
  return summary;
}

}  // namespace rkhs
