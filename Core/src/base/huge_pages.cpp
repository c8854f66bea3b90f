// SPDX-License-Identifier: BSD-3-Clause
#include "afam/base/huge_pages.hpp"

#include <cstdlib>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace afam {

void* mapHugePages(size_t bytes) {
  const size_t size = hugePageRounded(bytes);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  // Map one huge page more, keep the aligned part, give the ends back.
  const size_t mapped = size + kHugePageBytes;
  void* p = mmap(nullptr, mapped, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) throw std::bad_alloc();
  char* base = static_cast<char*>(p);
  char* aligned = reinterpret_cast<char*>(hugePageRounded(reinterpret_cast<size_t>(base)));
  if (aligned > base) munmap(base, size_t(aligned - base));
  const size_t tail = size_t(base + mapped - (aligned + size));
  if (tail > 0) munmap(aligned + size, tail);
  madvise(aligned, size, MADV_HUGEPAGE);  // advice: without it the buffer still works
  return aligned;
#else
  void* p = std::aligned_alloc(kHugePageBytes, size);
  if (!p) throw std::bad_alloc();
  return p;
#endif
}

void unmapHugePages(void* p, size_t bytes) noexcept {
  if (!p) return;
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  munmap(p, hugePageRounded(bytes));
#else
  (void)bytes;
  std::free(p);
#endif
}

}  // namespace afam
