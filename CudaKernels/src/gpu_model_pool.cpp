// SPDX-License-Identifier: BSD-3-Clause
#include "afam/cuda/gpu_model_pool.hpp"

#include <cuda_runtime_api.h>

#include <cstring>
#include <vector>

#include "cuda_check.hpp"

namespace afam {

namespace {
constexpr size_t kInitialStaging = size_t(8) << 20;
}

struct GpuModelPool::Impl {
  struct Copy {
    size_t staging, arena, bytes;
  };
  int device = 0;
  PoolLedger ledger;
  void* arena = nullptr;
  cudaStream_t stream = nullptr;
  cudaEvent_t copiesDone = nullptr;
  unsigned char* staging = nullptr;
  size_t stagingCapacity = 0;
  size_t stagingUsed = 0;
  std::vector<Copy> pending;

  explicit Impl(size_t budget, int dev) : device(dev), ledger(budget) {}

  void release() noexcept {
    if (stream) (void)cudaStreamSynchronize(stream);
    if (copiesDone) (void)cudaEventDestroy(copiesDone);
    if (stream) (void)cudaStreamDestroy(stream);
    if (staging) (void)cudaFreeHost(staging);
    if (arena) (void)cudaFree(arena);
    (void)cudaGetLastError();
    copiesDone = nullptr;
    stream = nullptr;
    staging = nullptr;
    arena = nullptr;
  }

  void issue() {
    // Merge copies contiguous in both staging and arena into one cudaMemcpyAsync.
    size_t i = 0;
    while (i < pending.size()) {
      Copy run = pending[i++];
      while (i < pending.size() && pending[i].staging == run.staging + run.bytes &&
             pending[i].arena == run.arena + run.bytes) {
        run.bytes += pending[i++].bytes;
      }
      AFAM_CUDA_CHECK(cudaMemcpyAsync(static_cast<unsigned char*>(arena) + run.arena,
                                      staging + run.staging, run.bytes, cudaMemcpyHostToDevice,
                                      stream));
    }
    pending.clear();
    AFAM_CUDA_CHECK(cudaEventRecord(copiesDone, stream));
  }

  void reserveStaging(size_t bytes) {
    if (stagingUsed + bytes <= stagingCapacity) return;
    // Staging is full: send what it holds and wait until it has left, then reuse or grow it.
    issue();
    AFAM_CUDA_CHECK(cudaEventSynchronize(copiesDone));
    stagingUsed = 0;
    if (bytes > stagingCapacity) {
      size_t grown = stagingCapacity ? stagingCapacity : kInitialStaging;
      while (grown < bytes) grown *= 2;
      if (staging) AFAM_CUDA_CHECK(cudaFreeHost(staging));
      staging = nullptr;
      stagingCapacity = 0;
      AFAM_CUDA_CHECK(cudaMallocHost(reinterpret_cast<void**>(&staging), grown));
      stagingCapacity = grown;
    }
  }
};

GpuModelPool::GpuModelPool(size_t budgetBytes, int device)
    : impl_(std::make_unique<Impl>(budgetBytes, device)) {
  try {
    AFAM_CUDA_CHECK(cudaSetDevice(device));
    AFAM_CUDA_CHECK(cudaMalloc(&impl_->arena, impl_->ledger.stats().capacityBytes
                                                  ? impl_->ledger.stats().capacityBytes
                                                  : 256));
    AFAM_CUDA_CHECK(cudaStreamCreateWithFlags(&impl_->stream, cudaStreamNonBlocking));
    AFAM_CUDA_CHECK(cudaEventCreateWithFlags(&impl_->copiesDone, cudaEventDisableTiming));
    AFAM_CUDA_CHECK(cudaMallocHost(reinterpret_cast<void**>(&impl_->staging), kInitialStaging));
    impl_->stagingCapacity = kInitialStaging;
    AFAM_CUDA_CHECK(cudaEventRecord(impl_->copiesDone, impl_->stream));
  } catch (...) {
    impl_->release();
    throw;
  }
}

GpuModelPool::~GpuModelPool() { impl_->release(); }

void GpuModelPool::beginFrame() {
  if (!impl_->pending.empty()) impl_->issue();
  AFAM_CUDA_CHECK(cudaEventSynchronize(impl_->copiesDone));
  impl_->stagingUsed = 0;
  impl_->ledger.beginFrame();
}

size_t GpuModelPool::acquire(uint64_t key, const void* host, size_t bytes) {
  const PoolLedger::Placement place = impl_->ledger.acquire(key, bytes);
  if (place.uploadNeeded && bytes > 0) {
    // Copy whole 256-byte granules (the ledger allocates those), so neighbouring uploads merge.
    const size_t padded = (bytes + 255) & ~size_t(255);
    impl_->reserveStaging(padded);
    unsigned char* dst = impl_->staging + impl_->stagingUsed;
    std::memcpy(dst, host, bytes);
    std::memset(dst + bytes, 0, padded - bytes);
    impl_->pending.push_back({impl_->stagingUsed, place.offset, padded});
    impl_->stagingUsed += padded;
  }
  return place.offset;
}

void GpuModelPool::flush() {
  if (!impl_->pending.empty()) impl_->issue();
}

void GpuModelPool::clear() {
  flush();
  AFAM_CUDA_CHECK(cudaStreamSynchronize(impl_->stream));
  impl_->ledger.clear();
}

const void* GpuModelPool::arena() const { return impl_->arena; }
void* GpuModelPool::stream() const { return impl_->stream; }
int GpuModelPool::device() const { return impl_->device; }
const PoolStats& GpuModelPool::stats() const { return impl_->ledger.stats(); }
const PoolLedger& GpuModelPool::ledger() const { return impl_->ledger; }

}  // namespace afam
