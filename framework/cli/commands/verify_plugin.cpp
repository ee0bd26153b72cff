// `rkhs-study verify-plugin MODULE`: the kernel contract and the declared smoothness of a
// plugin module's kernels (docs/writing-a-kernel.md). Exit 0 when every check passed, 1 when
// some failed (the report says which).
#include <iostream>

#include "commands/commands.hpp"
#include "rkhs/verify/plugin_verification.hpp"

namespace rkhs::cli {

int command_verify_plugin(const std::string& file) {
  const auto verification = verify_plugin(file);
  std::cout << format_verification(verification);
  return verification.passed() ? exit_ok : exit_failed_trials;
}

}  // namespace rkhs::cli
