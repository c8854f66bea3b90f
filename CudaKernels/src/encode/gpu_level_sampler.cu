// SPDX-License-Identifier: BSD-3-Clause
// The coarse levels filtered on the GPU (make_gpu_level_sampler.hpp): the volume copied into
// device memory as stored, plane by plane as the encoder's range scan reads it; each z-row of
// blocks one kernel, a thread a sample, filteredSample's sums (level_filter.hpp, compiled with
// -fmad=false, so the floats are the CPU's), the row's taps uploaded with it and its samples
// brought back through pinned memory.
#include <cuda_runtime.h>

#include <algorithm>
#include <cstring>
#include <mutex>
#include <vector>

#include "afam/cuda/common/gpu_error.hpp"
#include "afam/cuda/encode/make_gpu_level_sampler.hpp"
#include "afam/ranks/device_selection.hpp"
#include "afam/sampling/level_filter.hpp"
#include "common/cuda_check.hpp"
#include "common/growing_array.hpp"
#include "encode/gpu_volume_copy.hpp"

namespace afam {

namespace {

using cuda_detail::GrowingArray;

/// One block of a row on the device: where its x and y taps start, its sample counts, and where
/// its samples start in the row's output.
struct RowBlock {
  uint64_t x = 0, y = 0, out = 0;
  int nx = 0, ny = 0;
};

constexpr int kThreads = 256;

template <typename T>
__global__ void __launch_bounds__(kThreads)
    filterRowKernel(const T* volume, int64_t rowSize, int64_t planeSize, const int64_t* index,
                    const double* weight, const uint64_t* first, const RowBlock* blocks,
                    uint64_t zFirst, int nz, float* out) {
  const RowBlock b = blocks[blockIdx.y];
  const int64_t plane = int64_t(b.nx) * b.ny, count = plane * nz;
  const int64_t s = int64_t(blockIdx.x) * kThreads + threadIdx.x;
  if (s >= count) return;
  const int k = int(s / plane), j = int((s % plane) / b.nx), i = int(s % b.nx);
  const AxisTapsView tx{index, weight, first + b.x}, ty{index, weight, first + b.y},
      tz{index, weight, first + zFirst};
  out[b.out + uint64_t(s)] = filteredSample(volume, rowSize, planeSize, tx, ty, tz, i, j, k);
}

class GpuLevelSampler final : public LevelSampler {
 public:
  GpuLevelSampler(int device, size_t budget) : device_(device), budget_(budget) {
    AFAM_CUDA_CHECK(cudaSetDevice(device));
    cudaDeviceProp prop{};
    AFAM_CUDA_CHECK(cudaGetDeviceProperties(&prop, device));
    name_ = prop.name;
    AFAM_CUDA_CHECK(cudaStreamCreateWithFlags(&stream_, cudaStreamNonBlocking));
  }
  ~GpuLevelSampler() override { (void)cudaStreamDestroy(stream_); }

  bool reserve(Index3 dims, SampleType type, std::string& why) override;
  void load(int64_t z0, int64_t nz, const void* samples) override;
  void sampleRow(const Partition& part, int level, const std::vector<Int3>& blocks, bool ghost,
                 LevelSampling sampling, std::vector<std::vector<float>*>& out,
                 const BlockLoop& loop) override;
  void release() override {
    volume_.release();
    taps_.release();
    out_.release();
    staging_.release();
  }
  std::string description() const override { return name_; }
  GpuVolumeCopy copy() const { return {volume_.data, dims_, type_, device_}; }

 private:
  /// Launches the row's kernel for the volume's type.
  void launch(const RowTaps& taps, const std::vector<RowBlock>& blocks, uint64_t largest);

  int device_;
  size_t budget_;
  std::string name_;
  cudaStream_t stream_ = nullptr;
  Index3 dims_{};
  SampleType type_ = SampleType::UInt8;
  size_t planeBytes_ = 0;
  GrowingArray volume_, taps_, out_, staging_{true};
};

bool GpuLevelSampler::reserve(Index3 dims, SampleType type, std::string& why) {
  if (!levelSamplerHolds(type)) {
    why = std::string("the GPU's copy holds 1- and 2-byte integers and float32, not ") +
          sampleTypeName(type);
    return false;
  }
  AFAM_CUDA_CHECK(cudaSetDevice(device_));
  planeBytes_ = size_t(dims[0] * dims[1]) * size_t(sampleTypeSize(type));
  const size_t bytes = planeBytes_ * size_t(dims[2]);
  size_t free = 0, total = 0;
  AFAM_CUDA_CHECK(cudaMemGetInfo(&free, &total));
  const size_t held = volume_.bytes;  // a copy of the encode before, reused or freed
  const size_t budget =
      budget_ > 0
          ? budget_
          : (free + held > kGpuEncodeReserveBytes ? free + held - kGpuEncodeReserveBytes : 0);
  if (bytes > budget) {
    why = "the volume's copy (" + std::to_string(bytes >> 20) + " MiB) is over " +
          (budget_ > 0 ? "its budget of " : "what the GPU can spare, ") +
          std::to_string(budget >> 20) + " MiB";
    release();
    return false;
  }
  dims_ = dims;
  type_ = type;
  try {
    volume_.reserve(bytes);
  } catch (const GpuOutOfMemory& e) {
    why = e.what();
    release();
    return false;
  }
  return true;
}

void GpuLevelSampler::load(int64_t z0, int64_t nz, const void* samples) {
  if (z0 < 0 || nz < 0 || z0 + nz > dims_[2])
    throw InvalidArgument("GpuLevelSampler: planes [" + std::to_string(z0) + ", " +
                          std::to_string(z0 + nz) + ") outside the volume's " +
                          std::to_string(dims_[2]));
  AFAM_CUDA_CHECK(cudaSetDevice(device_));  // the calling thread's device
  // From the scan's pageable buffer on this thread's own stream: the scan's threads copy at once.
  AFAM_CUDA_CHECK(cudaMemcpyAsync(volume_.as<unsigned char>() + size_t(z0) * planeBytes_, samples,
                                  size_t(nz) * planeBytes_, cudaMemcpyHostToDevice,
                                  cudaStreamPerThread));
  AFAM_CUDA_CHECK(cudaStreamSynchronize(cudaStreamPerThread));
}

void GpuLevelSampler::launch(const RowTaps& taps, const std::vector<RowBlock>& blocks,
                             uint64_t largest) {
  const size_t ni = taps.index.size() * sizeof(int64_t), nw = taps.weight.size() * sizeof(double),
               nf = taps.first.size() * sizeof(uint64_t), nb = blocks.size() * sizeof(RowBlock);
  std::vector<unsigned char> packed(ni + nw + nf + nb);
  std::memcpy(packed.data(), taps.index.data(), ni);
  std::memcpy(packed.data() + ni, taps.weight.data(), nw);
  std::memcpy(packed.data() + ni + nw, taps.first.data(), nf);
  std::memcpy(packed.data() + ni + nw + nf, blocks.data(), nb);
  taps_.reserve(packed.size());
  AFAM_CUDA_CHECK(
      cudaMemcpyAsync(taps_.data, packed.data(), packed.size(), cudaMemcpyHostToDevice, stream_));
  const auto* base = taps_.as<unsigned char>();
  const auto* index = reinterpret_cast<const int64_t*>(base);
  const auto* weight = reinterpret_cast<const double*>(base + ni);
  const auto* first = reinterpret_cast<const uint64_t*>(base + ni + nw);
  const auto* rb = reinterpret_cast<const RowBlock*>(base + ni + nw + nf);
  const dim3 grid(unsigned((largest + kThreads - 1) / kThreads), unsigned(blocks.size()));
  const int64_t X = dims_[0], XY = dims_[0] * dims_[1];
  withCopyType(type_, [&](auto* typed) {
    filterRowKernel<<<grid, kThreads, 0, stream_>>>(static_cast<decltype(typed)>(volume_.data), X,
                                                    XY, index, weight, first, rb, taps.z, taps.nz,
                                                    out_.as<float>());
  });
  AFAM_CUDA_CHECK(cudaGetLastError());
  // `packed` (host memory) outlives its copy to the device: the row waits for its kernel here.
  AFAM_CUDA_CHECK(cudaStreamSynchronize(stream_));
}

void GpuLevelSampler::sampleRow(const Partition& part, int level, const std::vector<Int3>& blocks,
                                bool ghost, LevelSampling sampling,
                                std::vector<std::vector<float>*>& out, const BlockLoop& loop) {
  if (blocks.empty()) return;
  AFAM_CUDA_CHECK(cudaSetDevice(device_));
  const RowTaps taps = rowTaps(part, level, blocks, ghost, sampling);
  std::vector<RowBlock> rb(blocks.size());
  uint64_t total = 0, largest = 0;
  for (size_t b = 0; b < blocks.size(); ++b) {
    rb[b] = {taps.blocks[b].x, taps.blocks[b].y, total, taps.blocks[b].nx, taps.blocks[b].ny};
    total += taps.samples(b);
    largest = std::max<uint64_t>(largest, taps.samples(b));
  }
  out_.reserve(total * sizeof(float));
  staging_.reserve(total * sizeof(float));
  launch(taps, rb, largest);
  AFAM_CUDA_CHECK(cudaMemcpyAsync(staging_.data, out_.data, total * sizeof(float),
                                  cudaMemcpyDeviceToHost, stream_));
  AFAM_CUDA_CHECK(cudaStreamSynchronize(stream_));
  auto copy = [&](int64_t b) {
    std::vector<float>& o = *out[size_t(b)];
    o.resize(taps.samples(size_t(b)));
    std::memcpy(o.data(), staging_.as<float>() + rb[size_t(b)].out, o.size() * sizeof(float));
  };
  if (loop)
    loop(int64_t(blocks.size()), copy);
  else
    for (size_t b = 0; b < blocks.size(); ++b) copy(int64_t(b));
}

}  // namespace

GpuVolumeCopy gpuVolumeCopy(const LevelSampler* sampler) {
  const auto* gpu = dynamic_cast<const GpuLevelSampler*>(sampler);
  return gpu ? gpu->copy() : GpuVolumeCopy{};
}

std::shared_ptr<LevelSampler> makeGpuLevelSampler(
    const std::function<void(const std::string&)>& report, int device, size_t volumeBudgetBytes) {
  std::string why;
  if (!gpuAvailable(&why)) {
    report(why);
    return nullptr;
  }
  try {
    return std::make_shared<GpuLevelSampler>(
        device >= 0 ? device : selectGpuDevice(gpuDeviceCount()), volumeBudgetBytes);
  } catch (const GpuError& e) {
    report(e.what());
    return nullptr;
  }
}

}  // namespace afam
