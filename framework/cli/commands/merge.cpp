// `rkhs-study merge INTO FROM... [--prefer source|destination]`: result stores (e.g. of shards)
// combined into one, all or nothing: every source record verified, conflicts (a trial stored
// with two different results) refused unless --prefer says which record wins, and everything
// written in one transaction (ResultStore::merge_from).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include "commands/commands.hpp"
#include "commands/common.hpp"
#include "rkhs/run/result_store.hpp"

namespace rkhs::cli {

int command_merge(const std::string& into_file, const std::vector<std::string>& from,
                  const std::string& prefer) {
  const auto preference = prefer == "source"        ? MergePreference::source
                          : prefer == "destination" ? MergePreference::destination
                                                    : MergePreference::refuse;
  // A merge that fails leaves no store behind where there was none.
  const bool existed = std::filesystem::exists(into_file);
  // SIGINT / SIGTERM stop the merge between batches of records: its one transaction is rolled
  // back and the destination left as it was.
  stop_at_signals();
  std::vector<MergedSource> merged;
  std::size_t held = 0;
  try {
    ResultStore into(into_file);
    merged = into.merge_from(std::vector<std::filesystem::path>(from.begin(), from.end()),
                             preference, stop_was_requested);
    into.checkpoint();
    held = into.size();
  } catch (const MergeInterrupted&) {
    if (!existed) remove_store_files(into_file);
    std::cerr << fmt::format(
        "rkhs-study: interrupted: nothing merged; {} (run the same command again to merge)\n",
        existed ? into_file + " is left as it was" : "no " + into_file + " was created");
    return exit_interrupted;
  } catch (...) {
    if (!existed) remove_store_files(into_file);
    throw;
  }
  for (const auto& source : merged) {
    std::cout << fmt::format("merged {} from {}: {} new, {} already held",
                             counted(source.records, "trial", "trials"), source.file, source.added,
                             source.same);
    if (source.replaced)
      std::cout << fmt::format(", {} replaced (--prefer source)", source.replaced);
    if (source.kept)
      std::cout << fmt::format(", {} different kept as they were (--prefer destination)",
                               source.kept);
    if (source.repaired)
      std::cout << fmt::format(", {} in place of records that did not verify", source.repaired);
    std::cout << "\n";
  }
  std::cout << fmt::format("{} holds {}\n", into_file, counted(held, "trial", "trials"));
  if (stop_was_requested())  // once the transaction was committed: too late to undo it
    std::cerr << fmt::format(
        "rkhs-study: the interruption came after the merge was committed: {} holds every "
        "merged trial\n",
        into_file);
  return exit_ok;
}

Command add_merge_command(CLI::App& app) {
  struct Arguments {
    std::string into, prefer;
    std::vector<std::string> from;
  };
  auto arguments = std::make_shared<Arguments>();
  auto* merge = app.add_subcommand(
      "merge",
      "combine result stores (e.g. of shards) into one, all or nothing: every source record "
      "verified, a trial stored with two different results refused unless --prefer says which "
      "record wins");
  merge->add_option("into", arguments->into, "the store to merge into (created if needed)")
      ->required();
  merge->add_option("from", arguments->from, "stores to copy from")
      ->required()
      ->check(CLI::ExistingPath);  // a FIFO or a directory: refused by its type
  merge
      ->add_option("--prefer", arguments->prefer,
                   "when a trial is stored with two different results: destination keeps the "
                   "record already there, source takes the one merged later (default: refuse "
                   "the merge)")
      ->check(CLI::IsMember({"source", "destination"}));
  return {merge, {}, [arguments](pipeline::Executor&) {
            return command_merge(arguments->into, arguments->from, arguments->prefer);
          }};
}

}  // namespace rkhs::cli
