// The allocation interposer of the rkhs-study command and of the test executable (never of the
// core library, whose users keep their own malloc, and never under the sanitizers, which
// interpose malloc themselves): malloc, free, calloc, realloc and the aligned allocation
// functions of glibc are replaced by versions that call glibc's own (__libc_malloc, ...) and
// count each block into the work counters current on the calling thread
// (rkhs/core/work_counters.hpp). Eigen allocates with std::malloc and the standard library's
// operator new calls malloc, so every heap block of a trial passes through here.
//
// A block counts its allocated size as free() will see it: malloc_usable_size, with blocks of
// 128 KiB and more rounded up to whole pages. glibc serves those from the heap or from mmap
// depending on a threshold that moves as the process runs (a process-wide history, so it
// depends on what other threads did); rounded this way both give the same count, ALIGN_UP(chunk
// + 8, page) for a chunk of the same request. Nothing here allocates; a reentrancy guard keeps a
// call made while counting (there is none today) from counting again.
#include <malloc.h>

#include <cerrno>
#include <cstddef>
#include <cstdint>

#include "rkhs/core/work_counters.hpp"

extern "C" {
void* __libc_malloc(std::size_t size) noexcept;
void __libc_free(void* block) noexcept;
void* __libc_calloc(std::size_t count, std::size_t size) noexcept;
void* __libc_realloc(void* block, std::size_t size) noexcept;
void* __libc_memalign(std::size_t alignment, std::size_t size) noexcept;
}

namespace {

constexpr std::size_t page = 4096;                // x86-64 and AArch64 (4 KiB pages)
constexpr std::size_t large_block = 128 * 1024;  // glibc's smallest mmap threshold

[[gnu::tls_model("initial-exec")]] thread_local bool counting = false;

std::uint64_t counted_size(void* block) noexcept {
  const std::size_t usable = malloc_usable_size(block);
  if (usable + 16 < large_block) return usable;
  return (usable + 16 + page - 1) / page * page;
}

void note(void* block, bool allocated) noexcept {
  if (!block || counting || !rkhs::current_work_counters()) return;
  counting = true;
  rkhs::count_heap_block(counted_size(block), allocated);
  counting = false;
}

bool power_of_two(std::size_t value) noexcept { return value && !(value & (value - 1)); }

// Announces the interposer to the core library when the executable starts.
[[maybe_unused]] const bool announced = [] {
  rkhs::enable_allocation_tracking();
  return true;
}();

}  // namespace

extern "C" {

void* malloc(std::size_t size) noexcept {
  void* block = __libc_malloc(size);
  note(block, true);
  return block;
}

void free(void* block) noexcept {
  note(block, false);
  __libc_free(block);
}

void* calloc(std::size_t count, std::size_t size) noexcept {
  void* block = __libc_calloc(count, size);
  note(block, true);
  return block;
}

void* realloc(void* block, std::size_t size) noexcept {
  // The old block's size is read before glibc may release it.
  const bool tracked = block && !counting && rkhs::current_work_counters();
  const std::uint64_t old_size = tracked ? counted_size(block) : 0;
  void* moved = __libc_realloc(block, size);
  if (tracked && (moved || size == 0)) {  // realloc(p, 0) frees p; a failure keeps it
    counting = true;
    rkhs::count_heap_block(old_size, false);
    counting = false;
  }
  note(moved, true);
  return moved;
}

void* memalign(std::size_t alignment, std::size_t size) noexcept {
  void* block = __libc_memalign(alignment, size);
  note(block, true);
  return block;
}

void* aligned_alloc(std::size_t alignment, std::size_t size) noexcept {
  return memalign(alignment, size);
}

int posix_memalign(void** out, std::size_t alignment, std::size_t size) noexcept {
  if (!power_of_two(alignment) || alignment % sizeof(void*) != 0) return EINVAL;
  void* block = memalign(alignment, size);
  if (!block) return ENOMEM;
  *out = block;
  return 0;
}

void* valloc(std::size_t size) noexcept { return memalign(page, size); }

void* pvalloc(std::size_t size) noexcept { return memalign(page, (size + page - 1) / page * page); }

}  // extern "C"
