// libFuzzer harness: stored records of the result store (framework/src/run/result_store.cpp)
// decoded from arbitrary bytes. Each input is read three ways:
//   1. as the stored record of the trial "fuzz" (rkhs::read_record: format line, checksum,
//      metric names, the trial's fields, one value per metric name);
//   2. resealed: the text before its checksum line (all of it when it has none) with the
//      checksum it needs, so that what lies behind the checksum is reached;
//   3. as the payload MPI ranks send (rkhs::deserialize_result).
// read_record never throws for bad text (RecordCheck::problem says what is wrong), and
// deserialize_result throws std::invalid_argument only; anything else is a bug. A record that
// verifies must say nothing is wrong, hold one value per metric name and read back the same
// after store_record writes it again.
#include <cstddef>
#include <cstdint>
#include <exception>
#include <stdexcept>
#include <string>
#include <string_view>

#include "fuzz_support.hpp"
#include "rkhs/core/sha256.hpp"
#include "rkhs/run/result_store.hpp"

namespace {

const std::string hash = "fuzz";
// The row's study and key (covered by the checksum of records of format 3).
const std::string study = "fuzz", key = "n=1";

// The record with `body` (its lines before the checksum line) sealed for `hash`.
std::string sealed(std::string body) {
  if (!body.empty() && body.back() != '\n') body += '\n';
  return body + "checksum " + rkhs::sha256_hex(hash + "\n" + body) + "\n";
}

void check_record(std::string_view text) {
  const auto check = rkhs::read_record(hash, study, key, text);
  if (!check.sound()) {
    if (check.problem.empty()) std::abort();
    return;
  }
  if (!check.problem.empty() || check.old_format) std::abort();
  if (check.result->metrics.size() != check.metric_names.size()) std::abort();
  // Written again and read back: the same record, the same result.
  const auto again = rkhs::store_record(hash, study, key, *check.result, check.metric_names);
  const auto reread = rkhs::read_record(hash, study, key, again, &check.metric_names);
  if (!reread.sound() || reread.metric_names != check.metric_names) std::abort();
  if (rkhs::serialize_result(*reread.result) != rkhs::serialize_result(*check.result)) std::abort();
  if (rkhs::store_record(hash, study, key, *reread.result, reread.metric_names) != again)
    std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    check_record(text);
    const auto at_checksum = text.rfind("\nchecksum ");
    check_record(sealed(std::string(
        text.substr(0, at_checksum == std::string_view::npos ? text.size() : at_checksum + 1))));
    try {
      const auto result = rkhs::deserialize_result(text);
      if (rkhs::serialize_result(rkhs::deserialize_result(rkhs::serialize_result(result))) !=
          rkhs::serialize_result(result))
        std::abort();
    } catch (const std::invalid_argument&) {
      // Not a trial's text: a correct refusal.
    }
  } catch (const std::exception& e) {
    rkhs::fuzz::unexpected_exception(e);
  }
  return 0;
}
