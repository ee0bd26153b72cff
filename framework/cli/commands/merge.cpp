// `rkhs-study merge INTO FROM...`: result stores (e.g. of shards) combined into one.
#include <fmt/format.h>

#include <iostream>

#include "commands/commands.hpp"
#include "commands/common.hpp"
#include "rkhs/run/result_store.hpp"

namespace rkhs::cli {

int command_merge(const std::string& into_file, const std::vector<std::string>& from) {
  ResultStore into(into_file);
  for (const auto& file : from) {
    const auto count = into.merge_from(file);
    std::cout << fmt::format("merged {} from {}\n", counted(count, "trial", "trials"), file);
  }
  std::cout << fmt::format("{} holds {}\n", into_file, counted(into.size(), "trial", "trials"));
  return exit_ok;
}

}  // namespace rkhs::cli
