// SPDX-License-Identifier: BSD-3-Clause
// Internal: the kernels and their launchers, compiled three times with different floating-point
// contracts (see kernel_launch.hpp): each .cu that includes this defines AFAM_KERNEL_NS first.
// The kernels call the shared afam::castRay / castRayWith (Core/include/afam/render/raycast.hpp);
// nothing of the ray's math is written here.
#include <cuda_runtime.h>

#include <string>

#include "afam/render/raycast.hpp"
#include "common/cuda_check.hpp"
#include "render/kernel_launch.hpp"

#ifndef AFAM_KERNEL_NS
#error "define AFAM_KERNEL_NS before including kernels.cuh"
#endif

namespace afam::AFAM_KERNEL_NS {

constexpr int kTileX = 16;
constexpr int kTileY = 8;

/// raycast.hpp's sampler with the spline degree fixed at compile time (P = -1: any degree), and
/// reading models kept as codes (Codes) or float32 points only (the common, faster copy).
template <int P, bool Codes>
using SamplerFor = ModelSamplerT<P, Codes>;

template <bool Shaded, int P, int MinBlocks = 0, bool Codes = false>
__global__ void __launch_bounds__(kTileX* kTileY, MinBlocks)
    fullKernel(const FrameView f, float4* __restrict__ image) {
  const int px = int(blockIdx.x) * kTileX + int(threadIdx.x);
  const int py = int(blockIdx.y) * kTileY + int(threadIdx.y);
  if (px >= f.camera.width || py >= f.camera.height) return;
  const RGBA c = castRayWith<Shaded>(f, SamplerFor<P, Codes>{}, px, py);
  image[int64_t(py) * f.camera.width + px] = make_float4(c.r, c.g, c.b, c.a);
}

/// Maximum / minimum / average intensity projection (FrameView::blendMode 1-3).
template <int P, bool Codes = false>
__global__ void __launch_bounds__(kTileX* kTileY)
    projectionKernel(const FrameView f, float4* __restrict__ image) {
  const int px = int(blockIdx.x) * kTileX + int(threadIdx.x);
  const int py = int(blockIdx.y) * kTileY + int(threadIdx.y);
  if (px >= f.camera.width || py >= f.camera.height) return;
  const RGBA c = castProjectionRayWith(f, SamplerFor<P, Codes>{}, px, py);
  image[int64_t(py) * f.camera.width + px] = make_float4(c.r, c.g, c.b, c.a);
}

template <bool Shaded, int P, bool Codes>
__global__ void __launch_bounds__(kTileX* kTileY)
    countingKernel(const FrameView f, unsigned long long* total) {
  const int px = int(blockIdx.x) * kTileX + int(threadIdx.x);
  const int py = int(blockIdx.y) * kTileY + int(threadIdx.y);
  if (px >= f.camera.width || py >= f.camera.height) return;
  unsigned count = 0;
  SampleCounter<SamplerFor<P, Codes>> sampler{{}, &count};
  (void)castRayWith<Shaded>(f, sampler, px, py);
  atomicAdd(total, (unsigned long long)count);
}

/// Baseline: the same rays and sample positions as castRayWith, but every sample in the box is
/// only looked up and evaluated (value + gradient); no TF, shading, compositing or early exit.
template <int P, bool Codes>
__global__ void __launch_bounds__(kTileX* kTileY)
    bareKernel(const FrameView f, float* __restrict__ sink, unsigned long long* total) {
  const int px = int(blockIdx.x) * kTileX + int(threadIdx.x);
  const int py = int(blockIdx.y) * kTileY + int(threadIdx.y);
  if (px >= f.camera.width || py >= f.camera.height) return;
  const SamplerFor<P, Codes> sampler{};
  float sum = 0.f;
  unsigned count = 0;
  RaySamples r;
  if (raySamples(f, px, py, r)) {
    for (int64_t k = r.kBegin; k <= r.kEnd; ++k) {
      const float t = sampleAt(r, k);
      const float p[3] = {r.o[0] + t * r.d[0], r.o[1] + t * r.d[1], r.o[2] + t * r.d[2]};
      float value = 0.f, g[3] = {0.f, 0.f, 0.f};
      if (!sampler.template sample<true>(f, p, value, g)) continue;
      sum += value + g[0] + g[1] + g[2];
      ++count;
    }
  }
  sink[int64_t(py) * f.camera.width + px] = sum;
  if (total) atomicAdd(total, (unsigned long long)count);
}

template <typename Kernel>
std::string describe(Kernel kernel, const char* name) {
  cudaFuncAttributes a{};
  if (cudaFuncGetAttributes(&a, kernel) != cudaSuccess) {
    (void)cudaGetLastError();
    return name;
  }
  return std::string(name) + ": " + std::to_string(a.numRegs) + " registers, " +
         std::to_string(a.localSizeBytes) + " bytes local";
}

struct LaunchConfig {
  dim3 grid, block;
};
LaunchConfig config(const FrameView& v) {
  return {dim3(unsigned((v.camera.width + kTileX - 1) / kTileX),
               unsigned((v.camera.height + kTileY - 1) / kTileY)),
          dim3(kTileX, kTileY)};
}

/// ", codes" in a kernel's name when it reads models kept as codes.
const char* codesTag(bool codes) { return codes ? ",codes" : ""; }

template <bool Shaded, int P, int MinBlocks = 0, bool Codes = false>
std::string launchFullT(const FrameView& d, float* image, cudaStream_t stream, bool describeIt) {
  const LaunchConfig c = config(d);
  fullKernel<Shaded, P, MinBlocks, Codes>
      <<<c.grid, c.block, 0, stream>>>(d, reinterpret_cast<float4*>(image));
  AFAM_CUDA_CHECK(cudaGetLastError());
  if (!describeIt) return {};
  const std::string name = std::string("full<") + (Shaded ? "shaded" : "unshaded") +
                           ",p=" + (P < 0 ? std::string("any") : std::to_string(P)) +
                           (MinBlocks > 1 ? ",minBlocks=" + std::to_string(MinBlocks) : "") +
                           codesTag(Codes) + ">";
  return describe(fullKernel<Shaded, P, MinBlocks, Codes>, name.c_str());
}

template <int P, bool Codes = false>
std::string launchProjectionT(const FrameView& d, float* image, cudaStream_t stream,
                              bool describeIt) {
  const LaunchConfig c = config(d);
  projectionKernel<P, Codes><<<c.grid, c.block, 0, stream>>>(d, reinterpret_cast<float4*>(image));
  AFAM_CUDA_CHECK(cudaGetLastError());
  if (!describeIt) return {};
  const std::string name = "projection<mode=" + std::to_string(d.blendMode) +
                           ",p=" + (P < 0 ? std::string("any") : std::to_string(P)) +
                           codesTag(Codes) + ">";
  return describe(projectionKernel<P, Codes>, name.c_str());
}

template <bool Shaded, int P, bool Codes>
void launchCountT(const FrameView& d, unsigned long long* total, cudaStream_t stream) {
  const LaunchConfig c = config(d);
  countingKernel<Shaded, P, Codes><<<c.grid, c.block, 0, stream>>>(d, total);
  AFAM_CUDA_CHECK(cudaGetLastError());
}

template <int P, bool Codes>
std::string launchBareT(const FrameView& d, float* sink, unsigned long long* total,
                        cudaStream_t stream, bool describeIt) {
  const LaunchConfig c = config(d);
  bareKernel<P, Codes><<<c.grid, c.block, 0, stream>>>(d, sink, total);
  AFAM_CUDA_CHECK(cudaGetLastError());
  if (!describeIt) return {};
  const std::string name =
      "bare<p=" + (P < 0 ? std::string("any") : std::to_string(P)) + codesTag(Codes) + ">";
  return describe(bareKernel<P, Codes>, name.c_str());
}

/// A frame whose pool holds models as codes: the copies that read them, for the common degree 2
/// and any other (kept to these few: each copy costs compile time three times over).
std::string launchFullCodes(bool shaded, int p, const FrameView& d, float* image, cudaStream_t s,
                            bool describeIt) {
  if (d.blendMode != kBlendComposite) return launchProjectionT<-1, true>(d, image, s, describeIt);
  if (p == 2)
    return shaded ? launchFullT<true, 2, 0, true>(d, image, s, describeIt)
                  : launchFullT<false, 2, 0, true>(d, image, s, describeIt);
  return shaded ? launchFullT<true, -1, 0, true>(d, image, s, describeIt)
                : launchFullT<false, -1, 0, true>(d, image, s, describeIt);
}

std::string launchFull(bool shaded, int p, const FrameView& d, float* image, cudaStream_t s,
                       bool describeIt, int minBlocks, bool codes) {
  if (codes) return launchFullCodes(shaded, p, d, image, s, describeIt);
  if (d.blendMode != kBlendComposite) {  // projections: no shading, one kernel per degree
    switch (p) {
      case 1:
        return launchProjectionT<1>(d, image, s, describeIt);
      case 2:
        return launchProjectionT<2>(d, image, s, describeIt);
      case 3:
        return launchProjectionT<3>(d, image, s, describeIt);
      default:
        return launchProjectionT<-1>(d, image, s, describeIt);
    }
  }
  // Occupancy variant (8 blocks of 128 threads per SM: at most 64 registers), degree 2 only.
  if (minBlocks == 8 && p == 2)
    return shaded ? launchFullT<true, 2, 8>(d, image, s, describeIt)
                  : launchFullT<false, 2, 8>(d, image, s, describeIt);
  if (shaded) {
    switch (p) {
      case 1:
        return launchFullT<true, 1>(d, image, s, describeIt);
      case 2:
        return launchFullT<true, 2>(d, image, s, describeIt);
      case 3:
        return launchFullT<true, 3>(d, image, s, describeIt);
      case 4:
        return launchFullT<true, 4>(d, image, s, describeIt);
      case 5:
        return launchFullT<true, 5>(d, image, s, describeIt);
      default:
        return launchFullT<true, -1>(d, image, s, describeIt);
    }
  }
  switch (p) {
    case 1:
      return launchFullT<false, 1>(d, image, s, describeIt);
    case 2:
      return launchFullT<false, 2>(d, image, s, describeIt);
    case 3:
      return launchFullT<false, 3>(d, image, s, describeIt);
    case 4:
      return launchFullT<false, 4>(d, image, s, describeIt);
    case 5:
      return launchFullT<false, 5>(d, image, s, describeIt);
    default:
      return launchFullT<false, -1>(d, image, s, describeIt);
  }
}

void launchCount(bool shaded, int p, const FrameView& d, unsigned long long* total, cudaStream_t s,
                 bool codes) {
  // Counting is for benchmarks: the common degree 2 and the generic path are enough.
  if (codes)
    return shaded ? launchCountT<true, -1, true>(d, total, s)
                  : launchCountT<false, -1, true>(d, total, s);
  if (shaded) {
    if (p == 2) return launchCountT<true, 2, false>(d, total, s);
    return launchCountT<true, -1, false>(d, total, s);
  }
  if (p == 2) return launchCountT<false, 2, false>(d, total, s);
  return launchCountT<false, -1, false>(d, total, s);
}

std::string launchBare(int p, const FrameView& d, float* sink, unsigned long long* total,
                       cudaStream_t s, bool describeIt, bool codes) {
  if (codes) return launchBareT<-1, true>(d, sink, total, s, describeIt);
  if (p == 2) return launchBareT<2, false>(d, sink, total, s, describeIt);
  return launchBareT<-1, false>(d, sink, total, s, describeIt);
}

}  // namespace afam::AFAM_KERNEL_NS
