// A shared library that proves it was loaded: its constructor, which runs inside dlopen before
// any check of the module, creates the file that RKHS_TEST_LOAD_MARKER names. Not built against
// the framework (the loader refuses it afterwards). `report` must never load it
// (tests/cli/test_cli.cpp).
#include <cstdio>
#include <cstdlib>

namespace {

__attribute__((constructor)) void mark_loaded() {
  if (const char* file = std::getenv("RKHS_TEST_LOAD_MARKER"))
    if (std::FILE* out = std::fopen(file, "w")) {
      std::fputs("loaded\n", out);
      std::fclose(out);
    }
}

}  // namespace
