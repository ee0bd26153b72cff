// libFuzzer harness: a study file parsed from arbitrary bytes (rkhs::parse_study). Any input may
// be refused with a StudyError, the one exception parse_study documents; any other exception, a
// crash, a leak, an out-of-bounds read or undefined behaviour is a bug (the harness is built with
// ASan and UBSan, asan preset). A study that parses must hold what the parser promises: every
// extent of the domain within [Domain::min_extent, Domain::max_extent], n values that increase,
// a grid within [limits] trials, a name of at most 100 characters.
//
// Inputs that name `plugins` are skipped: a study file may load plugin modules by path, and the
// fuzzer must not dlopen whatever shared library a mutation happens to name.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <string_view>

#include "fuzz_support.hpp"
#include "rkhs/study/study.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  if (text.find("plugins") != std::string_view::npos) return 0;
  try {
    const auto study = rkhs::parse_study(text, "fuzz.toml");
    for (int a = 0; a < study.domain.dimension; ++a)
      if (!(study.domain.extent(a) >= rkhs::Domain::min_extent &&
            study.domain.extent(a) <= rkhs::Domain::max_extent))
        std::abort();
    if (study.name.size() > 100) std::abort();
    if (study.n_values.empty() || study.n_values.front() < 1) std::abort();
    for (std::size_t i = 1; i < study.n_values.size(); ++i)
      if (!(study.n_values[i - 1] < study.n_values[i])) std::abort();
  } catch (const rkhs::StudyError&) {
    // A refusal is a correct answer to a malformed study file.
  } catch (const std::exception& e) {
    rkhs::fuzz::unexpected_exception(e);
  }
  return 0;
}
