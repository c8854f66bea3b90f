// SPDX-License-Identifier: BSD-3-Clause
#define ZSTD_STATIC_LINKING_ONLY  // ZSTD_createCCtx_advanced and ZSTD_customMem
#include <zstd.h>

#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>

#include "afam/base/huge_pages.hpp"
#include "afam/entropy/zstd_contexts.hpp"

namespace afam {

namespace {

// Each block is preceded by its size (zstd frees by address only), in a header that keeps the
// 64-byte alignment zstd's workspace prefers.
constexpr size_t kHeader = 64;

void* allocateFor(void*, size_t bytes) {
  const size_t total = bytes + kHeader;
  void* p = nullptr;
  try {
    p = total >= kHugePageMinBytes ? mapHugePages(total)
                                   : std::aligned_alloc(64, (total + 63) / 64 * 64);
  } catch (const std::bad_alloc&) {
    return nullptr;  // zstd reports the failure
  }
  if (!p) return nullptr;
  std::memcpy(p, &total, sizeof total);
  return static_cast<char*>(p) + kHeader;
}

void freeFor(void*, void* address) {
  if (!address) return;
  void* p = static_cast<char*>(address) - kHeader;
  size_t total;
  std::memcpy(&total, p, sizeof total);
  if (total >= kHugePageMinBytes)
    unmapHugePages(p, total);
  else
    std::free(p);
}

constexpr ZSTD_customMem kMemory{allocateFor, freeFor, nullptr};

struct CCtxDeleter {
  void operator()(ZSTD_CCtx* c) const { ZSTD_freeCCtx(c); }
};
struct DCtxDeleter {
  void operator()(ZSTD_DCtx* c) const { ZSTD_freeDCtx(c); }
};

}  // namespace

ZSTD_CCtx* threadCCtx() {
  thread_local std::unique_ptr<ZSTD_CCtx, CCtxDeleter> ctx(ZSTD_createCCtx_advanced(kMemory));
  if (!ctx) throw std::bad_alloc();
  return ctx.get();
}

ZSTD_DCtx* threadDCtx() {
  thread_local std::unique_ptr<ZSTD_DCtx, DCtxDeleter> ctx(ZSTD_createDCtx_advanced(kMemory));
  if (!ctx) throw std::bad_alloc();
  return ctx.get();
}

}  // namespace afam
