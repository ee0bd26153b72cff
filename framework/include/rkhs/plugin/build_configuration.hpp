#pragma once
// The build configuration a plugin module must share with the rkhs-study that loads it, beyond
// what the plugin ABI version says (plugin/module.hpp).
//
// The ABI version covers the framework's types. It cannot cover how the code on both sides was
// compiled, and some of that still matters after the boundary stopped handing owned objects
// across (no virtual returns an Eigen object or a container; module.hpp):
//   compiler      family and major version: the C++ ABI of the standard library's types the
//                 boundary still passes (std::string in PluginInfo, std::function), and the
//                 layout of the framework's classes as each compiler lays them out;
//   Eigen         its version and EIGEN_MAX_ALIGN_BYTES: the layout and alignment of the Eigen
//                 objects a plugin reads and writes through references (Plant::A(),
//                 Eigen::Ref outputs), and which allocator Eigen's inline code calls;
//   vectorisation the instruction-set class the compiler targets (SSE2, AVX, AVX-512, from its
//                 predefined macros): it sets Eigen's alignment and packet code; a plugin built
//                 with -mavx or -march=native against a generic rkhs-study is refused here
//                 rather than corrupting memory or faulting on an older processor later;
//   sanitizer     AddressSanitizer or ThreadSanitizer on or off: an instrumented side and an
//                 uninstrumented side disagree about the heap and about synchronisation;
//   debug library _GLIBCXX_DEBUG changes the layout of every standard container.
//
// RKHS_BUILD_CONFIGURATION is a macro on purpose: it is evaluated in the translation unit that
// expands it, so the framework's value is that of the framework's build and a module's (returned
// by rkhs_plugin_build_configuration(), defined by RKHS_PLUGIN_MODULE) that of the module's. The
// loader compares the two field by field before the module may register anything, and a
// mismatch is refused with both configurations named (plugin_loader.hpp). The struct holds ints
// only, so reading a module's is sound whatever it was built with.

#include <Eigen/Core>
#include <string>

namespace rkhs {

/// Compiler families (BuildConfiguration::compiler).
enum class CompilerFamily : int { other = 0, gcc = 1, clang = 2 };
/// Vectorisation classes, from the compiler's predefined macros (BuildConfiguration).
enum class VectorisationClass : int { none = 0, sse2 = 1, avx = 2, avx512 = 3, neon = 4 };
/// Sanitizers that change the program's view of memory or threads (BuildConfiguration).
enum class SanitizerKind : int { none = 0, address = 1, thread = 2 };

/// What must be equal on both sides of the plugin boundary (see the file comment). Plain ints:
/// a C-compatible layout.
struct BuildConfiguration {
  int compiler;         ///< CompilerFamily
  int compiler_major;   ///< __GNUC__ or __clang_major__
  int eigen_version;    ///< world * 10000 + major * 100 + minor (30400 for 3.4.0)
  int max_align_bytes;  ///< EIGEN_MAX_ALIGN_BYTES
  int vectorisation;    ///< VectorisationClass
  int sanitizer;        ///< SanitizerKind
  int debug_library;    ///< 1 with _GLIBCXX_DEBUG, else 0

  friend bool operator==(const BuildConfiguration&, const BuildConfiguration&) = default;
};

/// "gcc 12, Eigen 3.4.0 (alignment 16 bytes), SSE2, no sanitizer".
std::string describe(const BuildConfiguration& configuration);
/// The fields in which `a` and `b` differ, each as "vectorisation AVX against SSE2" or "Eigen
/// alignment 32 bytes against 16 bytes" (a's value first), joined by "; ". Empty when equal.
std::string describe_difference(const BuildConfiguration& a, const BuildConfiguration& b);
/// The configuration the rkhs_study library was built with.
BuildConfiguration framework_build_configuration() noexcept;

}  // namespace rkhs

#if defined(__clang__)
#define RKHS_DETAIL_COMPILER ::rkhs::CompilerFamily::clang
#define RKHS_DETAIL_COMPILER_MAJOR __clang_major__
#elif defined(__GNUC__)
#define RKHS_DETAIL_COMPILER ::rkhs::CompilerFamily::gcc
#define RKHS_DETAIL_COMPILER_MAJOR __GNUC__
#else
#define RKHS_DETAIL_COMPILER ::rkhs::CompilerFamily::other
#define RKHS_DETAIL_COMPILER_MAJOR 0
#endif

#if defined(__AVX512F__)
#define RKHS_DETAIL_VECTORISATION ::rkhs::VectorisationClass::avx512
#elif defined(__AVX__)
#define RKHS_DETAIL_VECTORISATION ::rkhs::VectorisationClass::avx
#elif defined(__SSE2__)
#define RKHS_DETAIL_VECTORISATION ::rkhs::VectorisationClass::sse2
#elif defined(__ARM_NEON)
#define RKHS_DETAIL_VECTORISATION ::rkhs::VectorisationClass::neon
#else
#define RKHS_DETAIL_VECTORISATION ::rkhs::VectorisationClass::none
#endif

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define RKHS_DETAIL_ASAN 1
#endif
#if __has_feature(thread_sanitizer)
#define RKHS_DETAIL_TSAN 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(RKHS_DETAIL_ASAN)
#define RKHS_DETAIL_SANITIZER ::rkhs::SanitizerKind::address
#elif defined(__SANITIZE_THREAD__) || defined(RKHS_DETAIL_TSAN)
#define RKHS_DETAIL_SANITIZER ::rkhs::SanitizerKind::thread
#else
#define RKHS_DETAIL_SANITIZER ::rkhs::SanitizerKind::none
#endif

#if defined(_GLIBCXX_DEBUG)
#define RKHS_DETAIL_DEBUG_LIBRARY 1
#else
#define RKHS_DETAIL_DEBUG_LIBRARY 0
#endif

/// The build configuration of the translation unit that expands it (see the file comment).
#define RKHS_BUILD_CONFIGURATION                                                     \
  (::rkhs::BuildConfiguration{                                                       \
      static_cast<int>(RKHS_DETAIL_COMPILER), RKHS_DETAIL_COMPILER_MAJOR,            \
      EIGEN_WORLD_VERSION * 10000 + EIGEN_MAJOR_VERSION * 100 + EIGEN_MINOR_VERSION, \
      EIGEN_MAX_ALIGN_BYTES, static_cast<int>(RKHS_DETAIL_VECTORISATION),            \
      static_cast<int>(RKHS_DETAIL_SANITIZER), RKHS_DETAIL_DEBUG_LIBRARY})
