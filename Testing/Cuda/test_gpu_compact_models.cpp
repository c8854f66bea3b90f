// SPDX-License-Identifier: BSD-3-Clause
// Models the cache keeps in their compact form (compact_form.hpp) drawn on the GPU: the pool
// expands a compact model to float32 points as it uploads it (GpuModelPool::acquireCompact) while
// it has room, and keeps it compact when the frame's floats would take most of it
// (GpuPoolModels::Auto), read by the kernels that read codes; either way the image is the one drawn
// from float32 models bit for bit, the RAM cache holds fewer bytes, and a model the pool holds
// costs nothing in the next frame.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include "../Core/render_test_util.hpp"
#include "afam/cuda/render/gpu_caster.hpp"
#include "afam/cuda/render/gpu_renderer.hpp"
#include "afam/render/renderer.hpp"

namespace afam {

namespace {

/// A field with noise above the bound: its finest blocks are interpolants with rounded points.
std::shared_ptr<const AfamFile> noisyFile() {
  auto file = afam_test::encodeNoisyField(EntropyStage::Auto, 0.03);
  int64_t rounded = 0;
  for (const ModelEntry& e : file->entries()) rounded += e.roundedPoints;
  EXPECT_GE(rounded, 32);
  return file;
}

RenderOptions noisyOptions() {
  RenderOptions o;
  o.threads = 2;
  o.sampleDistance = 0.01f;
  o.lod.bandWidth = 100;  // every block at the finest level
  o.hasTransferFunction = true;
  o.transferFunction = afam_test::ramp(0.0, 1.0, 0.3, 0.2);
  return o;
}

/// Gives `r` a GPU caster with a pool of `poolBytes` that decodes nothing itself (every model
/// through the RAM cache); returns it.
GpuCaster* useGpu(Renderer& r, size_t poolBytes) {
  auto c = GpuCaster::create(poolBytes, 2,
                             [](const std::string& m) { std::printf("gpu: %s\n", m.c_str()); });
  if (!c) return nullptr;
  c->setDecodeOnGpu(false);
  GpuCaster* caster = c.get();
  r.setCaster(std::move(c));
  return caster;
}

/// A view, the same view again (every model resident) and another.
std::array<Camera, 3> threeViews() {
  return {Camera::lookAt({1.2, 1.4, 1.0}, {0, 0, 0}, {0, 0, 1}, 50, 96, 96),
          Camera::lookAt({1.2, 1.4, 1.0}, {0, 0, 0}, {0, 0, 1}, 50, 96, 96),
          Camera::lookAt({-1.3, 0.8, 1.1}, {0, 0, 0}, {0, 0, 1}, 45, 96, 96)};
}

/// Draws `view` with both renderers (on the GPU, both) and expects the same image bit for bit.
void drawBoth(Renderer& got, Renderer& want, const Camera& view, int index, FrameStats& a,
              FrameStats& b) {
  const ImageRGBA x = got.renderFrame(view, a);
  const ImageRGBA y = want.renderFrame(view, b);
  EXPECT_TRUE(a.cast.onGpu && b.cast.onGpu) << "view " << index;
  ASSERT_EQ(x.rgba.size(), y.rgba.size());
  EXPECT_EQ(0, std::memcmp(x.rgba.data(), y.rgba.data(), x.rgba.size() * sizeof(float)))
      << "view " << index;
}

}  // namespace

TEST(GpuCompactModels, ThePoolExpandsCompactModelsOnceAndDrawsTheFloatsImage) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  const auto file = noisyFile();
  const RenderOptions o = noisyOptions();
  RenderOptions asFloats = o;
  asFloats.compactModels = false;
  Renderer compact(file, o), floats(file, asFloats);
  GpuCaster* roomy = useGpu(compact, size_t(256) << 20);
  ASSERT_TRUE(roomy && useGpu(floats, size_t(256) << 20));
  const std::array<Camera, 3> views = threeViews();
  for (int v = 0; v < 3; ++v) {
    FrameStats a, b;
    drawBoth(compact, floats, views[v], v, a, b);
    EXPECT_EQ(roomy->gpu().lastCompactSlots(), 0) << "a pool with room holds float32 points";
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

TEST(GpuCompactModels, APoolUnderPressureKeepsThemCompactAndDrawsTheSameImage) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  const auto file = noisyFile();
  const RenderOptions o = noisyOptions();
  Renderer pressed(file, o), floats(file, o);
  // The frame's models take 3.9 MB as float32: more than three quarters of a 4 MiB pool.
  GpuCaster* small = useGpu(pressed, size_t(4) << 20);
  GpuCaster* expanding = useGpu(floats, size_t(16) << 20);
  ASSERT_TRUE(small && expanding);
  expanding->gpu().setPoolModels(GpuPoolModels::Floats);
  const std::array<Camera, 3> views = threeViews();
  int64_t compactSlots[3] = {0, 0, 0};
  for (int v = 0; v < 3; ++v) {
    FrameStats a, b;
    drawBoth(pressed, floats, views[v], v, a, b);
    compactSlots[v] = small->gpu().lastCompactSlots();
    EXPECT_EQ(expanding->gpu().lastCompactSlots(), 0);
    if (v == 0) {
      EXPECT_GT(compactSlots[0], 32);
      EXPECT_GT(expanding->poolStats().residentBytes, small->poolStats().capacityBytes / 4 * 3);
      EXPECT_LT(2 * small->poolStats().residentBytes, expanding->poolStats().residentBytes);
    }
    if (v == 1) {
      EXPECT_EQ(a.cast.modelsUploaded, 0);  // the same view: every model resident, still compact
      EXPECT_EQ(compactSlots[1], compactSlots[0]);
    }
    std::printf(
        "[gpu-compact-pool] view %d: slots=%lld compact=%lld uploaded=%lld pool %zu B "
        "(floats: %zu B), kernel %s\n",
        v, (long long)a.slots, (long long)compactSlots[v], (long long)a.cast.modelsUploaded,
        small->poolStats().residentBytes, expanding->poolStats().residentBytes,
        small->gpu().lastKernelInfo().c_str());
  }
  EXPECT_GT(compactSlots[2], 0);  // resident compact models stay compact
  // A pool with room expands them: the same file in a 16 MiB pool left to decide.
  expanding->gpu().setPoolModels(GpuPoolModels::Auto);
  expanding->gpu().pool().clear();
  FrameStats c;
  (void)floats.renderFrame(views[0], c);
  EXPECT_EQ(expanding->gpu().lastCompactSlots(), 0);
}

}  // namespace afam
