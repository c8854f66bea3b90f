// SPDX-License-Identifier: BSD-3-Clause
// Ray length limits from a depth buffer in device memory, one thread per image pixel, with the
// CPU's math (afam/scene/depth_limits.hpp). Compiled with -fmad=false: the same roundings as the
// CPU's rayLengthsFromDepth, so GPU and CPU frames stop their rays at the same samples.
#include "afam/scene/depth_limits.hpp"
#include "render/kernel_launch.hpp"

namespace afam::kernels_depth {
namespace {

__global__ void depthLimits(DepthToRay t, const float* depth, float* limits,
                            unsigned long long* limited) {
  const int x = int(blockIdx.x * blockDim.x + threadIdx.x);
  const int y = int(blockIdx.y * blockDim.y + threadIdx.y);  // y = 0: bottom row
  if (x >= t.width || y >= t.height) return;
  const float l = rayLimitFromDepth(t, depth, x, y);
  limits[static_cast<long long>(t.height - 1 - y) * t.width + x] = l;  // row 0 = top
  if (!isinf(l)) atomicAdd(limited, 1ull);
}

}  // namespace

void launchDepthLimits(const DepthToRay& t, const float* depth, float* limits,
                       unsigned long long* limited, cudaStream_t s) {
  const dim3 block(16, 16);
  const dim3 grid((unsigned(t.width) + 15) / 16, (unsigned(t.height) + 15) / 16);
  depthLimits<<<grid, block, 0, s>>>(t, depth, limits, limited);
}

}  // namespace afam::kernels_depth
