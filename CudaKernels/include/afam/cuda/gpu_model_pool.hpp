// SPDX-License-Identifier: BSD-3-Clause
// GPU model pool: one device arena that keeps micro-models across frames. Per frame, only models
// that are not resident are copied, asynchronously, from pinned staging memory on the pool's
// stream; least-recently-used models of earlier frames are evicted under the byte budget.
// Plain C++ header (no CUDA types): the stream and pointers are handed out as void*.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "afam/cuda/pool_ledger.hpp"

namespace afam {

class GpuModelPool {
 public:
  /// Allocates `budgetBytes` of device memory on `device`. Throws GpuOutOfMemory when the device
  /// cannot give that much (retry smaller, or use the CPU), GpuError for other CUDA failures.
  explicit GpuModelPool(size_t budgetBytes, int device = 0);
  ~GpuModelPool();
  GpuModelPool(const GpuModelPool&) = delete;
  GpuModelPool& operator=(const GpuModelPool&) = delete;

  /// Starts a frame. Waits until the previous frame's uploads have left the staging memory.
  void beginFrame();
  /// Byte offset of model `key` in the arena. When it is not resident, its `bytes` bytes at `host`
  /// are copied to pinned staging now and queued for upload. Throws GpuOutOfMemory when this
  /// frame's models do not fit in the budget (nothing is evicted that this frame uses).
  size_t acquire(uint64_t key, const void* host, size_t bytes);
  /// Issues the queued uploads on stream() (asynchronous; kernels later on that stream see them).
  void flush();
  /// Drops every resident model.
  void clear();

  const void* arena() const;  ///< device pointer to the arena base
  void* stream() const;       ///< the cudaStream_t all uploads (and the renderer's kernels) use
  int device() const;
  const PoolStats& stats() const;
  const PoolLedger& ledger() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace afam
