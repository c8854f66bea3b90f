// SPDX-License-Identifier: BSD-3-Clause
// Models decoded on the GPU inside the frame (the cache's stored form,
// GpuModelPool::acquireStored): a renderer whose misses are decoded on the GPU draws the image of
// one whose models were decoded on the CPU, bit for bit, frame after frame; its RAM cache holds the
// compressed payloads (fewer bytes); no block is reported damaged.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <memory>

#include "../Core/render_test_util.hpp"
#include "afam/cuda/render/gpu_caster.hpp"
#include "afam/cuda/render/gpu_renderer.hpp"
#include "afam/render/renderer.hpp"

namespace afam {
namespace {

RenderOptions options() {
  RenderOptions o;
  o.threads = 2;
  o.cache = CacheBudget{};
  o.sampleDistance = 0.01f;
  o.lod.bandWidth = 100;  // every block at the finest level
  o.hasTransferFunction = true;
  o.transferFunction = afam_test::ramp(0.0, 1.0, 0.3, 0.2);
  return o;
}

std::unique_ptr<GpuCaster> caster(bool decodeOnGpu) {
  auto c = GpuCaster::create(size_t(256) << 20, 2,
                             [](const std::string& m) { std::printf("gpu: %s\n", m.c_str()); });
  if (c) c->setDecodeOnGpu(decodeOnGpu);
  return c;
}

}  // namespace

TEST(GpuDecodedFrames, MissesDecodedOnTheGpuDrawTheImageOfCpuDecodedModels) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  const auto file = afam_test::encodeNoisyField(EntropyStage::Lanes);
  int64_t lanes = 0;
  for (const ModelEntry& e : file->entries()) lanes += gpuDecodesEntry(e) && e.coded;
  ASSERT_GT(lanes, 8);
  Renderer onGpu(file, options()), onCpu(file, options());
  onGpu.setCaster(caster(true));
  onCpu.setCaster(caster(false));
  const Camera views[] = {Camera::lookAt({1.2, 1.4, 1.0}, {0, 0, 0}, {0, 0, 1}, 50, 96, 96),
                          Camera::lookAt({-1.3, 0.8, 1.1}, {0, 0, 0}, {0, 0, 1}, 45, 96, 96),
                          Camera::lookAt({0.2, -1.6, 0.7}, {0, 0, 0}, {0, 0, 1}, 55, 96, 96)};
  for (const Camera& c : views) {
    FrameStats a, b;
    const ImageRGBA got = onGpu.renderFrame(c, a);
    const ImageRGBA want = onCpu.renderFrame(c, b);
    ASSERT_TRUE(a.cast.onGpu && b.cast.onGpu);
    EXPECT_TRUE(a.cast.damaged.empty()) << a.cast.damaged[0].second;
    EXPECT_TRUE(a.damageReports.empty());
    ASSERT_EQ(got.rgba.size(), want.rgba.size());
    EXPECT_EQ(0, std::memcmp(got.rgba.data(), want.rgba.data(), got.rgba.size() * sizeof(float)));
    std::printf("[gpu-decode] slots=%lld uploaded=%lld cache %llu B (decoded on the CPU: %llu B)\n",
                (long long)a.slots, (long long)a.cast.modelsUploaded,
                (unsigned long long)a.cacheBytes, (unsigned long long)b.cacheBytes);
  }
  EXPECT_LT(onGpu.cache().residentBytes(), onCpu.cache().residentBytes());  // compressed
}

}  // namespace afam
