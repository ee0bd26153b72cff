#pragma once
// Shared by the libFuzzer harnesses of tests/fuzz/: what a harness does with an exception it does
// not accept as a refusal of its input (a bug: a crash for libFuzzer and for the replay).

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <typeinfo>

namespace rkhs::fuzz {

/// Prints the exception's type and message, then aborts.
[[noreturn]] inline void unexpected_exception(const std::exception& e) {
  std::fprintf(stderr, "fuzz: unexpected exception %s: %s\n", typeid(e).name(), e.what());
  std::fflush(stderr);
  std::abort();
}

}  // namespace rkhs::fuzz
