// libFuzzer harness: a study file parsed from arbitrary bytes (rkhs::parse_study). Any input may
// be refused with a StudyError or another std::exception; none may crash, leak, read out of
// bounds or trigger undefined behaviour (the harness is built with ASan and UBSan, asan preset).
//
// Inputs that name `plugins` are skipped: a study file may load plugin modules by path, and the
// fuzzer must not dlopen whatever shared library a mutation happens to name.
#include <cstddef>
#include <cstdint>
#include <exception>
#include <string_view>

#include "rkhs/study/study.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  if (text.find("plugins") != std::string_view::npos) return 0;
  try {
    (void)rkhs::parse_study(text, "fuzz.toml");
  } catch (const std::exception&) {
    // A refusal is a correct answer to a malformed study file.
  }
  return 0;
}
