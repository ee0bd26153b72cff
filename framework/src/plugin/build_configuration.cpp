#include "rkhs/plugin/build_configuration.hpp"

#include <fmt/format.h>

#include <vector>

namespace rkhs {

namespace {

std::string compiler_name(const BuildConfiguration& c) {
  switch (static_cast<CompilerFamily>(c.compiler)) {
    case CompilerFamily::gcc:
      return fmt::format("gcc {}", c.compiler_major);
    case CompilerFamily::clang:
      return fmt::format("clang {}", c.compiler_major);
    case CompilerFamily::other:
      break;
  }
  return fmt::format("compiler {} {}", c.compiler, c.compiler_major);
}

std::string eigen_name(const BuildConfiguration& c) {
  return fmt::format("Eigen {}.{}.{}", c.eigen_version / 10000, c.eigen_version / 100 % 100,
                     c.eigen_version % 100);
}

std::string alignment_name(const BuildConfiguration& c) {
  return fmt::format("{} bytes", c.max_align_bytes);
}

std::string vectorisation_name(const BuildConfiguration& c) {
  switch (static_cast<VectorisationClass>(c.vectorisation)) {
    case VectorisationClass::none:
      return "no vectorisation";
    case VectorisationClass::sse2:
      return "SSE2";
    case VectorisationClass::avx:
      return "AVX";
    case VectorisationClass::avx512:
      return "AVX-512";
    case VectorisationClass::neon:
      return "NEON";
  }
  return fmt::format("vectorisation class {}", c.vectorisation);
}

std::string sanitizer_name(const BuildConfiguration& c) {
  switch (static_cast<SanitizerKind>(c.sanitizer)) {
    case SanitizerKind::none:
      return "no sanitizer";
    case SanitizerKind::address:
      return "AddressSanitizer";
    case SanitizerKind::thread:
      return "ThreadSanitizer";
  }
  return fmt::format("sanitizer {}", c.sanitizer);
}

std::string library_name(const BuildConfiguration& c) {
  return c.debug_library ? "_GLIBCXX_DEBUG" : "release standard library";
}

// The table of fields: what each is called in a difference, and how its value reads.
struct Field {
  const char* what;
  bool (*differs)(const BuildConfiguration&, const BuildConfiguration&);
  std::string (*name)(const BuildConfiguration&);
};
const Field fields[] = {
    {"compiler",
     [](const BuildConfiguration& a, const BuildConfiguration& b) {
       return a.compiler != b.compiler || a.compiler_major != b.compiler_major;
     },
     compiler_name},
    {"Eigen version",
     [](const BuildConfiguration& a, const BuildConfiguration& b) {
       return a.eigen_version != b.eigen_version;
     },
     eigen_name},
    {"Eigen alignment",
     [](const BuildConfiguration& a, const BuildConfiguration& b) {
       return a.max_align_bytes != b.max_align_bytes;
     },
     alignment_name},
    {"vectorisation",
     [](const BuildConfiguration& a, const BuildConfiguration& b) {
       return a.vectorisation != b.vectorisation;
     },
     vectorisation_name},
    {"sanitizer",
     [](const BuildConfiguration& a, const BuildConfiguration& b) {
       return a.sanitizer != b.sanitizer;
     },
     sanitizer_name},
    {"standard library",
     [](const BuildConfiguration& a, const BuildConfiguration& b) {
       return a.debug_library != b.debug_library;
     },
     library_name},
};

}  // namespace

std::string describe(const BuildConfiguration& c) {
  std::string out = fmt::format("{}, {} (alignment {}), {}, {}", compiler_name(c), eigen_name(c),
                                alignment_name(c), vectorisation_name(c), sanitizer_name(c));
  if (c.debug_library) out += ", _GLIBCXX_DEBUG";
  return out;
}

std::string describe_difference(const BuildConfiguration& a, const BuildConfiguration& b) {
  std::string out;
  for (const auto& field : fields)
    if (field.differs(a, b))
      out += fmt::format("{}{} {} against {}", out.empty() ? "" : "; ", field.what, field.name(a),
                         field.name(b));
  return out;
}

BuildConfiguration framework_build_configuration() noexcept {
  return RKHS_BUILD_CONFIGURATION;
}

}  // namespace rkhs
