// SPDX-License-Identifier: BSD-3-Clause
// The DS baseline through 3D textures (the paper's "state of the art multi-resolution framework
// through down sampling utilizing GPU 3D texture"): raw (kSlotRaw) blocks live in CUDA arrays, a
// sample is one hardware-trilinear fetch and the gradient six more (central differences of one
// sample spacing). Ray setup, O(1) lookup, classification, shading and compositing are the shared
// castRayWith / toVoxel / lookupSlot of raycast.hpp; only the fetch differs from sampleRawSlot.
#include <cuda_runtime.h>

#include <string>

#include "afam/render/raycast.hpp"
#include "common/cuda_check.hpp"
#include "render/kernel_launch.hpp"

namespace afam::kernels_texture {

namespace {

constexpr int kTileX = 16;
constexpr int kTileY = 8;

struct TextureDsSampler {
  const cudaTextureObject_t* textures;

  template <bool WithGradient>
  __device__ __forceinline__ bool sample(const FrameView& f, const float* p, float& value,
                                         float* gradient) const {
    float x[3];
    const int32_t slot = locateSample(f, p, x);
    if (slot < 0) return false;
    const FrameSlot& s = f.slots[slot];
    float t[3], perVoxel[3];
    for (int a = 0; a < 3; ++a) {
      const int n = s.knots[a].ncp - 2;  // real samples; one ghost sample on each side
      perVoxel[a] = float(n - 1) * s.invExtent[a];
      // Padded sample coordinate as in sampleRawSlot, +0.5 for texel centres.
      t[a] = (x[a] - s.lo[a]) * perVoxel[a] + 1.5f;
    }
    const cudaTextureObject_t tex = textures[slot];
    value = tex3D<float>(tex, t[0], t[1], t[2]);
    if (WithGradient) {
      const float gv[3] = {0.5f *
                               (tex3D<float>(tex, t[0] + 1.f, t[1], t[2]) -
                                tex3D<float>(tex, t[0] - 1.f, t[1], t[2])) *
                               perVoxel[0],
                           0.5f *
                               (tex3D<float>(tex, t[0], t[1] + 1.f, t[2]) -
                                tex3D<float>(tex, t[0], t[1] - 1.f, t[2])) *
                               perVoxel[1],
                           0.5f *
                               (tex3D<float>(tex, t[0], t[1], t[2] + 1.f) -
                                tex3D<float>(tex, t[0], t[1], t[2] - 1.f)) *
                               perVoxel[2]};
      voxelToNormalisedGradient(f, gv, gradient);
    }
    return true;
  }
};

template <bool Shaded>
__global__ void __launch_bounds__(kTileX* kTileY)
    textureKernel(const FrameView f, const cudaTextureObject_t* __restrict__ textures,
                  float4* __restrict__ image, unsigned long long* total) {
  const int px = int(blockIdx.x) * kTileX + int(threadIdx.x);
  const int py = int(blockIdx.y) * kTileY + int(threadIdx.y);
  if (px >= f.camera.width || py >= f.camera.height) return;
  if (total) {
    unsigned count = 0;
    (void)castRayWith<Shaded>(f, SampleCounter<TextureDsSampler>{{textures}, &count}, px, py);
    atomicAdd(total, (unsigned long long)count);
    return;
  }
  const RGBA c = castRayWith<Shaded>(f, TextureDsSampler{textures}, px, py);
  image[int64_t(py) * f.camera.width + px] = make_float4(c.r, c.g, c.b, c.a);
}

}  // namespace

std::string launchDsTexture(bool shaded, const FrameView& d, const unsigned long long* textures,
                            float* image, unsigned long long* total, cudaStream_t s,
                            bool describeIt) {
  const dim3 grid(unsigned((d.camera.width + kTileX - 1) / kTileX),
                  unsigned((d.camera.height + kTileY - 1) / kTileY));
  const dim3 block(kTileX, kTileY);
  const auto* tex = reinterpret_cast<const cudaTextureObject_t*>(textures);
  auto* out = reinterpret_cast<float4*>(image);
  if (shaded)
    textureKernel<true><<<grid, block, 0, s>>>(d, tex, out, total);
  else
    textureKernel<false><<<grid, block, 0, s>>>(d, tex, out, total);
  AFAM_CUDA_CHECK(cudaGetLastError());
  if (!describeIt) return {};
  cudaFuncAttributes a{};
  const cudaError_t st = shaded ? cudaFuncGetAttributes(&a, textureKernel<true>)
                                : cudaFuncGetAttributes(&a, textureKernel<false>);
  if (st != cudaSuccess) {
    (void)cudaGetLastError();
    return "ds-texture";
  }
  return std::string("ds-texture<") + (shaded ? "shaded" : "unshaded") +
         ">: " + std::to_string(a.numRegs) + " registers, " + std::to_string(a.localSizeBytes) +
         " bytes local";
}

}  // namespace afam::kernels_texture
