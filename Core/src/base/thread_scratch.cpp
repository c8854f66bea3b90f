// SPDX-License-Identifier: BSD-3-Clause
#include "afam/base/thread_scratch.hpp"

#include "afam/base/huge_pages.hpp"

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <new>

namespace afam {

namespace {

std::atomic<uint64_t> held{0};

// A buffer of this size or more is mapped and unmapped on its own: freeing it returns its pages
// at once (a freed heap block of this size may stay resident in the thread's arena).
constexpr size_t kMapAtLeast = size_t(64) << 10;

size_t pageRounded(size_t bytes) {
  const size_t page = size_t(sysconf(_SC_PAGESIZE));
  return (bytes + page - 1) / page * page;
}

void* allocate(size_t bytes) {
  if (bytes >= kHugePageMinBytes) return mapHugePages(bytes);  // one fault a 2 MB, not 512
  if (bytes >= kMapAtLeast) {
    void* p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) throw std::bad_alloc();
    return p;
  }
  void* p = std::aligned_alloc(64, bytes);  // a multiple of 64 (threadScratch rounds)
  if (!p) throw std::bad_alloc();
  return p;
}

void deallocate(void* p, size_t bytes) {
  if (!p) return;
  if (bytes >= kHugePageMinBytes)
    unmapHugePages(p, bytes);
  else if (bytes >= kMapAtLeast)
    munmap(p, bytes);
  else
    std::free(p);
}

struct Slots {
  void* data[size_t(ScratchSlot::Count)] = {};
  size_t bytes[size_t(ScratchSlot::Count)] = {};
  void release(size_t keepBelow) {
    for (size_t s = 0; s < size_t(ScratchSlot::Count); ++s) {
      if (bytes[s] < keepBelow) continue;
      deallocate(data[s], bytes[s]);
      held.fetch_sub(bytes[s], std::memory_order_relaxed);
      data[s] = nullptr;
      bytes[s] = 0;
    }
  }
  ~Slots() { release(0); }
};

Slots& mine() {
  thread_local Slots slots;
  return slots;
}

}  // namespace

void* threadScratch(ScratchSlot slot, size_t bytes) {
  Slots& m = mine();
  const size_t s = size_t(slot);
  if (m.bytes[s] < bytes || !m.data[s]) {
    size_t size =
        bytes >= kMapAtLeast ? pageRounded(bytes) : (std::max<size_t>(bytes, 1) + 63) / 64 * 64;
    if (size >= kHugePageMinBytes) size = hugePageRounded(size);  // what allocate() maps
    void* p = allocate(size);
    deallocate(m.data[s], m.bytes[s]);
    held.fetch_add(size, std::memory_order_relaxed);
    held.fetch_sub(m.bytes[s], std::memory_order_relaxed);
    m.data[s] = p;
    m.bytes[s] = size;
  }
  return m.data[s];
}

void releaseThreadScratch() { mine().release(kMapAtLeast); }

void releaseAllThreadScratch() { mine().release(0); }

uint64_t threadScratchBytes() { return held.load(std::memory_order_relaxed); }

}  // namespace afam
