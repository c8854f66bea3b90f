// SPDX-License-Identifier: BSD-3-Clause
// Ray length limits computed on the GPU from a depth buffer in device memory (the mapper's
// CUDA-OpenGL path) equal the CPU's rayLengthsFromDepth bit for bit: same math
// (depth_limits.hpp), no contraction on either side. Perspective and parallel cameras, an image
// smaller than the depth tile (interactive frames), far-plane pixels left unlimited.
#include <cuda_runtime_api.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include "afam/cuda/common/gpu_error.hpp"
#include "afam/cuda/render/gpu_renderer.hpp"
#include "afam/scene/view_mapping.hpp"

namespace afam {
namespace {

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(GpuDepthLimits, EqualTheCpuLimitsBitForBit) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  GpuRenderer gpu(size_t(16) << 20);
  const int tileW = 53, tileH = 41, w = 40, h = 30;
  std::vector<float> depth(size_t(tileW) * tileH);
  for (int y = 0; y < tileH; ++y)
    for (int x = 0; x < tileW; ++x)  // a far-plane band, then a slanted surface
      depth[size_t(y) * tileW + x] =
          x < tileW / 3 ? 1.0f : 0.35f + 0.6f * float(x + 2 * y) / float(tileW + 2 * tileH);
  float* device = nullptr;
  ASSERT_EQ(cudaMalloc(reinterpret_cast<void**>(&device), depth.size() * sizeof(float)),
            cudaSuccess);
  ASSERT_EQ(cudaMemcpy(device, depth.data(), depth.size() * sizeof(float), cudaMemcpyHostToDevice),
            cudaSuccess);
  // A projective NDC -> world matrix with w > 0 over the NDC cube, and a non-trivial frame map.
  const std::array<double, 16> m{1.3, 0.2,  -0.1, 0.4, -0.3, 0.9,  0.25,  -0.2,
                                 0.1, -0.2, -1.1, 0.3, 0.02, 0.01, -0.45, 0.55};
  FrameMap map;
  map.linear = {0.8, 0.1, 0, -0.1, 0.9, 0.05, 0, 0.02, 1.1};
  map.offset = {0.1, -0.2, 0.05};
  for (const bool parallel : {false, true}) {
    const Camera cam = parallel
                           ? Camera::parallelLookAt({2.5, -1, 1.5}, {0, 0, 0}, {0, 0, 1}, 1.3, w, h)
                           : Camera::lookAt({2.5, -1, 1.5}, {0, 0, 0}, {0, 0, 1}, 35, w, h);
    std::vector<float> cpu, onGpu;
    const int64_t limited = rayLengthsFromDepth(depth.data(), tileW, tileH, m, map, cam, cpu);
    const DeviceDepth dd{device, depthToRay(tileW, tileH, m, map, cam)};
    const int64_t limitedGpu = gpu.depthLimitsToHost(dd, onGpu);
    size_t differing = 0;
    for (size_t i = 0; i < cpu.size(); ++i) differing += sameBits(cpu[i], onGpu[i]) ? 0 : 1;
    std::printf(
        "[gpu-depth] %s: %lld of %d pixels limited (GPU %lld), %zu limits differ in any bit\n",
        parallel ? "parallel" : "perspective", (long long)limited, w * h, (long long)limitedGpu,
        differing);
    EXPECT_EQ(limitedGpu, limited);
    EXPECT_GT(limited, int64_t(w * h / 2));
    EXPECT_LT(limited, int64_t(w * h));
    ASSERT_EQ(onGpu.size(), cpu.size());
    EXPECT_EQ(differing, 0u);
  }
  // A tile smaller than the image is refused by name, before anything runs.
  DeviceDepth bad{device,
                  depthToRay(tileW, tileH, m, map,
                             Camera::lookAt({2.5, -1, 1.5}, {0, 0, 0}, {0, 0, 1}, 35, w, h))};
  bad.toRay.tileWidth = 20;
  std::vector<float> unused;
  EXPECT_THROW(gpu.depthLimitsToHost(bad, unused), InvalidArgument);
  ASSERT_EQ(cudaFree(device), cudaSuccess);
}

}  // namespace
}  // namespace afam
