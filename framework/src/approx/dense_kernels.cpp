// The choice among the variants of dense_kernels.hpp.
#include "rkhs/approx/dense_kernels.hpp"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <initializer_list>

namespace rkhs::dense {

bool supported(const Kernels& variant) noexcept {
  if (&variant == &baseline_kernels) return true;
#if defined(__x86_64__) || defined(__i386__)
  __builtin_cpu_init();
  // GCC's checks include the operating system's support for the YMM and ZMM state.
  if (&variant == &avx2_kernels)
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  if (&variant == &avx512_kernels)
    return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
           __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx2") &&
           __builtin_cpu_supports("fma");
#endif
  return false;
}

namespace {
const Kernels& choose() noexcept {
  const Kernels* widest = &baseline_kernels;
  for (const Kernels* variant : {&avx2_kernels, &avx512_kernels})
    if (supported(*variant)) widest = variant;
  const char* asked = std::getenv("RKHS_STUDY_DENSE_KERNELS");
  if (!asked || !*asked) return *widest;
  for (const Kernels* variant : {&baseline_kernels, &avx2_kernels, &avx512_kernels})
    if (std::strcmp(asked, variant->instruction_set) == 0) {
      if (supported(*variant)) return *variant;
      std::fprintf(stderr,
                   "rkhs-study: RKHS_STUDY_DENSE_KERNELS=%s: this processor does not support "
                   "it; using %s\n",
                   asked, widest->instruction_set);
      return *widest;
    }
  std::fprintf(stderr,
               "rkhs-study: RKHS_STUDY_DENSE_KERNELS=%s is none of x86-64, avx2, avx512; using "
               "%s\n",
               asked, widest->instruction_set);
  return *widest;
}
}  // namespace

const Kernels& kernels() noexcept {
  static const Kernels& chosen = choose();
  return chosen;
}

}  // namespace rkhs::dense
