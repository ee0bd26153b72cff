// `rkhs-study verify-plugin MODULE`: the kernel contract and the declared smoothness of a
// plugin module's kernels (docs/writing-a-kernel.md). Exit 0 when every check passed, 1 when
// some failed (the report says which).
#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>

#include "commands/commands.hpp"
#include "rkhs/verify/plugin_verification.hpp"

namespace rkhs::cli {

int command_verify_plugin(const std::string& file) {
  const auto verification = verify_plugin(file);
  std::cout << format_verification(verification);
  return verification.passed() ? exit_ok : exit_failed_trials;
}

Command add_verify_plugin_command(CLI::App& app) {
  auto plugin = std::make_shared<std::string>();
  auto* verify =
      app.add_subcommand("verify-plugin",
                         "load a plugin module and check its kernels: the kernel contract, and the "
                         "declared smoothness against the measured power-function rate");
  verify->add_option("plugin", *plugin, "plugin module (.so)")->required();
  return {verify, {}, [plugin](pipeline::Executor&) { return command_verify_plugin(*plugin); }};
}

}  // namespace rkhs::cli
