// SPDX-License-Identifier: BSD-3-Clause
// Internal: launchers of the ray-casting kernels, one set per floating-point contract.
//   exact: nvcc -fmad=false, IEEE division and square root: the same roundings as the CPU caster
//          (g++ on x86-64 contracts nothing), so images agree to the last bits but powf.
//   fma:   nvcc's default (multiply-adds contracted to FMA).
//   fast:  -use_fast_math (FMA, approximate division, square root, powf; flush to zero).
#pragma once

#include <cuda_runtime_api.h>

#include <string>

#include "afam/render/raycast.hpp"
#include "afam/scene/depth_limits.hpp"

#define AFAM_DECLARE_KERNEL_SET(NS)                                                            \
  namespace afam::NS {                                                                         \
  /* Full ray caster (castRayWith<Shaded>), specialised on degree p in 1..5 (else generic).    \
     Returns the kernel's register / local-memory use when describe is set. minBlocks = 8      \
     picks the variant limited to 64 registers (degree 2 only), anything else the default.     \
     codes: some slot holds its model as codes (FrameSlot::codeWidth): the kernels that read   \
     them (degree 2 or generic); otherwise those reading float32 points only. */               \
  std::string launchFull(bool shaded, int p, const FrameView& d, float* image, cudaStream_t s, \
                         bool describe, int minBlocks, bool codes);                            \
  /* Untimed launch that counts evaluated samples into *total. */                              \
  void launchCount(bool shaded, int p, const FrameView& d, unsigned long long* total,          \
                   cudaStream_t s, bool codes);                                                \
  /* Bare value+gradient baseline along the same rays; counts samples when total != null. */   \
  std::string launchBare(int p, const FrameView& d, float* sink, unsigned long long* total,    \
                         cudaStream_t s, bool describe, bool codes);                           \
  }

AFAM_DECLARE_KERNEL_SET(kernels_exact)
AFAM_DECLARE_KERNEL_SET(kernels_fma)
AFAM_DECLARE_KERNEL_SET(kernels_fast)

namespace afam::kernels_texture {
/// DS baseline: raw slots through 3D textures (textures[s]: cudaTextureObject_t of slot s, device
/// memory). Counts ray samples into *total instead of writing the image when total != null.
std::string launchDsTexture(bool shaded, const FrameView& d, const unsigned long long* textures,
                            float* image, unsigned long long* total, cudaStream_t s, bool describe);
}  // namespace afam::kernels_texture

namespace afam::kernels_depth {
/// limits[width * height] (row 0 = top) from the tile's depth (row 0 = bottom) by
/// rayLimitFromDepth; adds the number of limited pixels to *limited.
void launchDepthLimits(const DepthToRay& t, const float* depth, float* limits,
                       unsigned long long* limited, cudaStream_t s);
}  // namespace afam::kernels_depth
