// The entry points of a plugin built against a future rkhs-study with another plugin ABI. Nothing
// else is safe to call: rkhs_plugin_register aborts if the loader ever calls it.
#include <cstdlib>

extern "C" {
[[gnu::visibility("default")]] int rkhs_plugin_abi_version() noexcept {
  return 999;
}
[[gnu::visibility("default")]] const char* rkhs_plugin_rkhs_study_version() noexcept {
  return "9.9.9";
}
[[gnu::visibility("default")]] const char* rkhs_plugin_name() noexcept {
  return "wrong_abi";
}
[[gnu::visibility("default")]] int rkhs_plugin_register() noexcept {
  std::abort();
}
}
