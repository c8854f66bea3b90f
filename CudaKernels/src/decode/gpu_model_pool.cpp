// SPDX-License-Identifier: BSD-3-Clause
#include "afam/cuda/decode/gpu_model_pool.hpp"

#include <cuda_runtime_api.h>

#include <cstring>
#include <vector>

#include "common/cuda_check.hpp"

namespace afam {

namespace {
constexpr size_t kInitialStaging = size_t(8) << 20;
constexpr size_t kInitialPayloads = size_t(4) << 20;
size_t align256(size_t bytes) { return (bytes + 255) & ~size_t(255); }
}  // namespace

struct GpuModelPool::Impl {
  struct Copy {
    size_t staging, target, bytes;
    bool toPayloads;  ///< into `payloads` (stored bytes to decode), else into the arena
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
  // Stored payloads of this frame's models, uploaded and decoded into the arena by flush().
  std::unique_ptr<GpuBlockDecoder> decoder;  // made for the first stored model
  unsigned char* payloads = nullptr;
  size_t payloadCapacity = 0, payloadUsed = 0;
  std::vector<GpuDecodeJob> jobs;
  std::vector<uint64_t> jobKeys, decodingKeys;  // queued; decoding (its statuses not taken yet)
  std::vector<std::pair<uint64_t, uint32_t>> failures;

  explicit Impl(size_t budget, int dev) : device(dev), ledger(budget) {}

  void release() noexcept {
    if (stream) (void)cudaStreamSynchronize(stream);
    decoder.reset();
    if (payloads) (void)cudaFree(payloads);
    payloads = nullptr;
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
    // Merge copies contiguous in both staging and target into one cudaMemcpyAsync.
    size_t i = 0;
    while (i < pending.size()) {
      Copy run = pending[i++];
      while (i < pending.size() && pending[i].toPayloads == run.toPayloads &&
             pending[i].staging == run.staging + run.bytes &&
             pending[i].target == run.target + run.bytes) {
        run.bytes += pending[i++].bytes;
      }
      unsigned char* base = run.toPayloads ? payloads : static_cast<unsigned char*>(arena);
      AFAM_CUDA_CHECK(cudaMemcpyAsync(base + run.target, staging + run.staging, run.bytes,
                                      cudaMemcpyHostToDevice, stream));
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

  /// Room for `bytes` more stored bytes in the device payload buffer (grown, its contents kept).
  void reservePayloads(size_t bytes) {
    if (payloadUsed + bytes <= payloadCapacity) return;
    size_t grown = payloadCapacity ? 2 * payloadCapacity : kInitialPayloads;
    while (grown < payloadUsed + bytes) grown *= 2;
    unsigned char* bigger = nullptr;
    AFAM_CUDA_CHECK(cudaMalloc(reinterpret_cast<void**>(&bigger), grown));
    if (payloadUsed > 0)  // after the copies already issued into the old buffer
      AFAM_CUDA_CHECK(
          cudaMemcpyAsync(bigger, payloads, payloadUsed, cudaMemcpyDeviceToDevice, stream));
    AFAM_CUDA_CHECK(cudaStreamSynchronize(stream));
    if (payloads) AFAM_CUDA_CHECK(cudaFree(payloads));
    payloads = bigger;
    payloadCapacity = grown;
  }

  /// Waits for the batch being decoded and keeps its failures (their models forgotten).
  void collectFailures() {
    if (decodingKeys.empty()) return;
    const std::vector<uint32_t>& status = decoder->wait();
    for (size_t j = 0; j < decodingKeys.size() && j < status.size(); ++j)
      if (status[j] != 0) {
        ledger.forget(decodingKeys[j]);
        failures.push_back({decodingKeys[j], status[j]});
      }
    decodingKeys.clear();
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
  // A frame that stopped short (a model that did not fit) left copies and decoding queued for
  // models it had placed: they are sent now, before this frame may evict those models and give
  // their room to others.
  if (!impl_->jobs.empty()) flush();
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
    impl_->pending.push_back({impl_->stagingUsed, place.offset, padded, false});
    impl_->stagingUsed += padded;
  }
  return place.offset;
}

size_t GpuModelPool::acquireCompact(uint64_t key, const float* data, CompactForm form, Int3 ncp,
                                    size_t bytes) {
  const GpuDecodeJob job = gpuCompactJob(form, ncp, 0, 0);
  return acquireStored(key, reinterpret_cast<const uint8_t*>(data), job.storedBytes, bytes, job);
}

size_t GpuModelPool::acquireStored(uint64_t key, const uint8_t* stored, size_t storedBytes,
                                   size_t bytes, GpuDecodeJob job) {
  Impl& m = *impl_;
  const PoolLedger::Placement place = m.ledger.acquire(key, bytes);
  if (place.uploadNeeded && bytes > 0) {
    const size_t padded = align256(storedBytes);
    m.reserveStaging(padded);
    m.reservePayloads(padded);
    unsigned char* dst = m.staging + m.stagingUsed;
    std::memcpy(dst, stored, storedBytes);
    std::memset(dst + storedBytes, 0, padded - storedBytes);
    m.pending.push_back({m.stagingUsed, m.payloadUsed, padded, true});
    job.payloadOffset = m.payloadUsed;
    job.storedBytes = storedBytes;
    job.outputOffset = place.offset / sizeof(float);
    m.jobs.push_back(job);
    m.jobKeys.push_back(key);
    m.stagingUsed += padded;
    m.payloadUsed += padded;
  }
  return place.offset;
}

void GpuModelPool::flush() {
  Impl& m = *impl_;
  if (!m.pending.empty()) m.issue();
  if (m.jobs.empty()) return;
  if (!m.decoder) m.decoder = std::make_unique<GpuBlockDecoder>(m.device);
  m.collectFailures();  // a batch still in flight: its statuses first
  m.decoder->decodeAsync(m.jobs, m.payloads, static_cast<float*>(m.arena), m.stream);
  m.decodingKeys.swap(m.jobKeys);
  m.jobs.clear();
  m.jobKeys.clear();
  m.payloadUsed = 0;  // later copies into it are ordered after this decoding on the stream
}

std::vector<std::pair<uint64_t, uint32_t>> GpuModelPool::takeDecodeFailures() {
  impl_->collectFailures();
  std::vector<std::pair<uint64_t, uint32_t>> out;
  out.swap(impl_->failures);
  return out;
}

void GpuModelPool::clear() {
  flush();
  AFAM_CUDA_CHECK(cudaStreamSynchronize(impl_->stream));
  impl_->collectFailures();
  impl_->failures.clear();
  impl_->ledger.clear();
}

const void* GpuModelPool::arena() const { return impl_->arena; }
void* GpuModelPool::stream() const { return impl_->stream; }
int GpuModelPool::device() const { return impl_->device; }
const PoolStats& GpuModelPool::stats() const { return impl_->ledger.stats(); }
const PoolLedger& GpuModelPool::ledger() const { return impl_->ledger; }

}  // namespace afam
