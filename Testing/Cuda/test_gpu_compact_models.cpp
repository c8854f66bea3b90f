// SPDX-License-Identifier: BSD-3-Clause
// Models the cache keeps in their compact form (compact_form.hpp) drawn on the GPU: the pool
// expands a compact model to float32 points as it uploads it (GpuModelPool::acquireCompact), so
// that the image is the one drawn from float32 models bit for bit, the RAM cache holds fewer
// bytes, and a model the pool holds costs nothing in the next frame.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <memory>

#include "../Core/render_test_util.hpp"
#include "afam/cuda/gpu_caster.hpp"
#include "afam/cuda/gpu_renderer.hpp"
#include "afam/render/renderer.hpp"

namespace afam {

TEST(GpuCompactModels, ThePoolExpandsCompactModelsOnceAndDrawsTheFloatsImage) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  // Noise above the bound: the finest blocks are interpolants with rounded points.
  const auto file = afam_test::encodeNoisyField(EntropyStage::Auto, 0.03);
  int64_t rounded = 0;
  for (const ModelEntry& e : file->entries()) rounded += e.roundedPoints;
  ASSERT_GE(rounded, 32);
  RenderOptions o;
  o.threads = 2;
  o.sampleDistance = 0.01f;
  o.lod.bandWidth = 100;  // every block at the finest level
  o.hasTransferFunction = true;
  o.transferFunction = afam_test::ramp(0.0, 1.0, 0.3, 0.2);
  RenderOptions asFloats = o;
  asFloats.compactModels = false;
  Renderer compact(file, o), floats(file, asFloats);
  for (Renderer* r : {&compact, &floats}) {
    auto c = GpuCaster::create(size_t(256) << 20, 2,
                               [](const std::string& m) { std::printf("gpu: %s\n", m.c_str()); });
    ASSERT_TRUE(c);
    c->setDecodeOnGpu(false);  // every model through the RAM cache
    r->setCaster(std::move(c));
  }
  const Camera views[] = {Camera::lookAt({1.2, 1.4, 1.0}, {0, 0, 0}, {0, 0, 1}, 50, 96, 96),
                          Camera::lookAt({1.2, 1.4, 1.0}, {0, 0, 0}, {0, 0, 1}, 50, 96, 96),
                          Camera::lookAt({-1.3, 0.8, 1.1}, {0, 0, 0}, {0, 0, 1}, 45, 96, 96)};
  for (int v = 0; v < 3; ++v) {
    FrameStats a, b;
    const ImageRGBA got = compact.renderFrame(views[v], a);
    const ImageRGBA want = floats.renderFrame(views[v], b);
    ASSERT_TRUE(a.cast.onGpu && b.cast.onGpu);
    ASSERT_EQ(got.rgba.size(), want.rgba.size());
    EXPECT_EQ(0, std::memcmp(got.rgba.data(), want.rgba.data(), got.rgba.size() * sizeof(float)))
        << "view " << v;
    EXPECT_EQ(a.cast.modelsUploaded, b.cast.modelsUploaded) << "view " << v;
    if (v == 0) {
      EXPECT_GT(a.cast.modelsUploaded, 32);
    }
    if (v == 1) {
      EXPECT_EQ(a.cast.modelsUploaded, 0);  // the same view: every model resident
    }
    std::printf("[gpu-compact] view %d: slots=%lld uploaded=%lld cache %llu B (floats: %llu B)\n",
                v, (long long)a.slots, (long long)a.cast.modelsUploaded,
                (unsigned long long)a.cacheBytes, (unsigned long long)b.cacheBytes);
  }
  EXPECT_LT(2 * compact.cache().residentBytes(), floats.cache().residentBytes());
}

}  // namespace afam
