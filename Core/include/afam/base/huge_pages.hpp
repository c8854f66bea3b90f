// SPDX-License-Identifier: BSD-3-Clause
// Large work buffers on transparent huge pages: a buffer of a megabyte or more is mapped on its
// own, 2 MB aligned, and marked for huge pages (Linux's madvise setting gives them to marked memory
// only). Its first touch then costs one page fault per 2 MB instead of 512: measured on a VM at
// ~9 us a fault, first touches were 10-30% of an encode's time. Smaller buffers, and systems
// without madvise, use operator new.
#pragma once

#include <cstddef>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace afam {

constexpr size_t kHugePageBytes = size_t(2) << 20;
constexpr size_t kHugePageMinBytes = size_t(1) << 20;  ///< smaller: operator new

/// `bytes` rounded up to whole huge pages: what mapHugePages maps for them.
constexpr size_t hugePageRounded(size_t bytes) {
  return (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
}

/// `bytes` (rounded up to whole huge pages) mapped on their own, 2 MB aligned and marked for huge
/// pages where the system has them (else ordinary pages); std::bad_alloc when none are left.
void* mapHugePages(size_t bytes);
/// Gives back what mapHugePages(bytes) mapped at p.
void unmapHugePages(void* p, size_t bytes) noexcept;

template <typename T>
class HugePageAllocator {
 public:
  using value_type = T;
  HugePageAllocator() = default;
  template <typename U>
  HugePageAllocator(const HugePageAllocator<U>&) noexcept {}

  T* allocate(size_t n) {
    const size_t bytes = n * sizeof(T);
    if (bytes >= kHugePageMinBytes) return static_cast<T*>(mapHugePages(bytes));
    return static_cast<T*>(::operator new(bytes));
  }

  void deallocate(T* p, size_t n) noexcept {
    if (n * sizeof(T) >= kHugePageMinBytes)
      unmapHugePages(p, n * sizeof(T));
    else
      ::operator delete(p);
  }

  /// resize() default-initializes (leaves a double or float as it was, no fill): a work buffer is
  /// written before it is read, and filling it first with zeros cost a pass over fresh pages.
  template <typename U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible<U>::value) {
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }

  template <typename U>
  bool operator==(const HugePageAllocator<U>&) const noexcept {
    return true;
  }
  template <typename U>
  bool operator!=(const HugePageAllocator<U>&) const noexcept {
    return false;
  }
};

/// A vector whose storage, once large, lies on huge pages (HugePageAllocator); resize(n) leaves
/// new elements of a trivial type uninitialized (resize(n, value) fills them).
template <typename T>
using HugePageVector = std::vector<T, HugePageAllocator<T>>;

/// Grows a work buffer to at least n elements without copying what it held (it is to be
/// overwritten) and without filling the new ones; a large enough buffer is left as it is.
template <typename T>
void growBuffer(HugePageVector<T>& buffer, size_t n) {
  if (buffer.size() >= n) return;
  buffer.clear();
  buffer.resize(n);
}

}  // namespace afam
