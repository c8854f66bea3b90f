// SPDX-License-Identifier: BSD-3-Clause
// Internal: device memory, or pinned host memory, that grows to the largest request and frees
// itself (the encoder's GPU parts keep their buffers between batches).
#pragma once

#include <cuda_runtime_api.h>

#include <algorithm>
#include <cstddef>

#include "common/cuda_check.hpp"

namespace afam::cuda_detail {

/// Device memory (or pinned host memory) that grows to the largest request seen and frees itself.
struct GrowingArray {
  explicit GrowingArray(bool pinnedHost = false) : pinned(pinnedHost) {}
  ~GrowingArray() { release(); }
  void release() {
    (void)(pinned ? cudaFreeHost(data) : cudaFree(data));
    data = nullptr;
    bytes = 0;
  }
  void reserve(size_t want) {
    if (want <= bytes) return;
    release();
    const size_t size = std::max<size_t>(want, 1);
    AFAM_CUDA_CHECK(pinned ? cudaMallocHost(&data, size) : cudaMalloc(&data, size));
    bytes = want;
  }
  template <typename T>
  T* as() const {
    return static_cast<T*>(data);
  }
  bool pinned = false;
  void* data = nullptr;
  size_t bytes = 0;
};

}  // namespace afam::cuda_detail
