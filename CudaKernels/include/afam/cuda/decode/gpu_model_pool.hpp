// SPDX-License-Identifier: BSD-3-Clause
// GPU model pool: one device arena that keeps micro-models across frames. Per frame, only models
// that are not resident are copied, asynchronously, from pinned staging memory on the pool's
// stream; least-recently-used models of earlier frames are evicted under the byte budget. A model
// given as its stored payload (acquireStored) costs the copy of its compressed bytes, and is
// decoded into its place on the GPU (gpu_block_decoder.hpp) before the frame's kernels run.
// Plain C++ header (no CUDA types): the stream and pointers are handed out as void*.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "afam/cuda/decode/gpu_block_decoder.hpp"
#include "afam/cuda/decode/pool_ledger.hpp"

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
  /// As acquire(), for a model given in its compact form (`data`, compact_form.hpp's `form`, `ncp`
  /// control points per axis, whose float32 points take `bytes`): when it is not resident, its
  /// table and codes are staged and uploaded (a quarter or half of its floats) and expanded into
  /// its place on the GPU by flush(), as a stored payload is decoded.
  size_t acquireCompact(uint64_t key, const float* data, CompactForm form, Int3 ncp, size_t bytes);
  /// As acquire(), for a model given as its stored payload (`stored`, `storedBytes` of them) that
  /// decodes to `bytes` bytes as `job` says (gpuDecodeJob: its kind and NCP; the pool sets its
  /// offsets): when it is not resident, its stored bytes are staged now, and uploaded and decoded
  /// into its place by flush().
  size_t acquireStored(uint64_t key, const uint8_t* stored, size_t storedBytes, size_t bytes,
                       GpuDecodeJob job);
  /// Issues the queued uploads on stream(), then the decoding of the stored payloads among them
  /// (asynchronous; kernels later on that stream see the models).
  void flush();
  /// The models decoded since the last call whose payloads did not decode: their keys and
  /// GpuDecodeStatus, after waiting for their decoding. They are no longer resident (their place
  /// holds no model).
  std::vector<std::pair<uint64_t, uint32_t>> takeDecodeFailures();
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
