// The choice among the variants of dense_kernels.hpp.
#include "rkhs/approx/dense_kernels.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <initializer_list>
#include <vector>

#include "rkhs/core/cancellation.hpp"
#include "rkhs/core/concurrency.hpp"

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

bool parallel_cholesky(const Kernels& variant, double* a, Index n, Index lda) {
  if (n < 512) return variant.cholesky(a, n, lda);
  // Eigen's partition (LLT.h, llt_inplace::blocked): panels of `block` columns.
  const Index block = std::min<Index>(std::max<Index>((n / 8 / 16) * 16, 8), 128);
  // Tiles of the panel's triangular solve (rows) and of the trailing update (a column strip of
  // `strip` columns, its diagonal square and its rows below in chunks of `chunk`).
  constexpr Index rows_per_solve = 512, strip = 256, chunk = 1024;
  auto at = [&](Index row, Index col) { return a + row + col * lda; };
  struct Tile {
    Index col0, cols, row0, rows;
  };
  std::vector<Tile> tiles;
  for (Index k = 0; k < n; k += block) {
    check_cancelled();
    const Index bs = std::min(block, n - k), rs = n - k - bs;
    if (!variant.cholesky_unblocked(at(k, k), bs, lda)) return false;
    if (rs == 0) break;
    const Index solves = (rs + rows_per_solve - 1) / rows_per_solve;
    run_parts(static_cast<std::size_t>(solves), [&](std::size_t part) {
      const Index row0 = static_cast<Index>(part) * rows_per_solve;
      variant.solve_right_lower_transposed(at(k, k), bs, lda, at(k + bs + row0, k),
                                           std::min(rows_per_solve, rs - row0), lda);
    });
    // A22 -= A21 A21^T on the lower triangle, A21 = a(k + bs.., k..k + bs).
    tiles.clear();
    for (Index col0 = 0; col0 < rs; col0 += strip) {
      const Index cols = std::min(strip, rs - col0);
      tiles.push_back({col0, cols, col0, cols});  // the diagonal square
      for (Index row0 = col0 + cols; row0 < rs; row0 += chunk)
        tiles.push_back({col0, cols, row0, std::min(chunk, rs - row0)});
    }
    const Index base = k + bs;
    run_parts(tiles.size(), [&](std::size_t t) {
      check_cancelled();  // a tile is at most 256 x 1024 x 128 multiply-adds
      const Tile& tile = tiles[t];
      if (tile.row0 == tile.col0)
        variant.subtract_gram_lower(at(base + tile.col0, k), tile.cols, bs, lda,
                                    at(base + tile.col0, base + tile.col0), lda);
      else
        variant.subtract_product_transposed(at(base + tile.row0, k), tile.rows, bs, lda,
                                            at(base + tile.col0, k), tile.cols, lda,
                                            at(base + tile.row0, base + tile.col0), lda);
    });
  }
  return true;
}

const Kernels& kernels() noexcept {
  static const Kernels& chosen = choose();
  return chosen;
}

}  // namespace rkhs::dense
