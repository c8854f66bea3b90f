// SPDX-License-Identifier: BSD-3-Clause
// Editing the transfer function, shading and sample distance with the GPU caster installed keeps
// the RAM cache and the GPU model pool: after the first frame, every edit renders with no cache
// miss and no upload, and each edited frame still equals the CPU's image of the same settings.
// A frame the caster leaves in device memory (FrameTargets::deviceRgba, as the VTK mapper's OpenGL
// buffer) holds the same image as one copied back to the host; the next frame without it goes
// to the host again.
#include <cuda_runtime_api.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "../Core/render_test_util.hpp"
#include "afam/cuda/common/gpu_error.hpp"
#include "afam/cuda/render/gpu_caster.hpp"
#include "afam/cuda/render/gpu_renderer.hpp"
#include "afam/render/renderer.hpp"

namespace afam {
namespace {

using afam_test::ramp;

/// A ramp over the file's values from 30% of its range, sample distance 0.01.
FrameSettings rampSettings(const AfamFile& file) {
  const double lo = file.header().valueMin, hi = file.header().valueMax;
  FrameSettings s;
  s.hasTransferFunction = true;
  s.transferFunction = ramp(lo, hi, lo + 0.3 * (hi - lo), 0.1);
  s.sampleDistance = 0.01f;
  return s;
}

double maxDiff(const ImageRGBA& a, const ImageRGBA& b) {
  double worst = 0;
  for (size_t i = 0; i < a.rgba.size(); ++i)
    worst = std::max(worst, double(std::fabs(a.rgba[i] - b.rgba[i])));
  return worst;
}

TEST(GpuFrameEdits, EditsKeepTheCacheAndTheGpuPool) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  auto file = afam_test::encodeMl(129, EncodingMode::Adaptive, 3, 8, 1e-3);
  const double lo = file->header().valueMin, hi = file->header().valueMax;
  RendererResources resources;
  resources.cache = CacheBudget{};
  FrameSettings s;
  s.hasTransferFunction = true;
  s.transferFunction = ramp(lo, hi, lo + 0.3 * (hi - lo), 0.1);
  s.lod.bandWidth = 100;  // every block at the finest level
  s.sampleDistance = 0.01f;
  Renderer gpu(file, resources, s), cpu(file, resources, s);
  std::unique_ptr<GpuCaster> owned =
      GpuCaster::create(size_t(512) << 20, resources.threads,
                        [](const std::string& m) { std::printf("gpu: %s\n", m.c_str()); });
  ASSERT_TRUE(owned);
  GpuCaster& caster = *owned;
  gpu.setCaster(std::move(owned));
  const Camera c = Camera::lookAt({0.9, 0.8, 0.7}, {0, 0, 0}, {0, 0, 1}, 60, 160, 160);
  FrameStats first, firstCpu;
  gpu.renderFrame(c, first);
  cpu.renderFrame(c, firstCpu);
  const uint64_t uploads = caster.poolStats().uploads;
  std::printf("[gpu-edits] first frame: %lld models, %llu misses, %llu uploads\n",
              (long long)first.slots, (unsigned long long)first.misses,
              (unsigned long long)uploads);
  ASSERT_GE(first.slots, 100);
  ASSERT_EQ(uploads, uint64_t(first.slots));

  FrameSettings edited = s;
  for (int step = 0; step < 7; ++step) {
    if (step < 5) {  // opacity and colour points, the TF's visible range kept
      edited.transferFunction.opacities.back().alpha = 0.5 + 0.1 * step;
      edited.transferFunction.colors[0].g = 0.1 * step;
    }
    if (step == 5) edited.shading = !edited.shading;
    if (step == 6) edited.sampleDistance = 0.007f;
    FrameStats sg, sc;
    const ImageRGBA ig = gpu.renderFrame(c, edited, sg), ic = cpu.renderFrame(c, edited, sc);
    const double d = maxDiff(ig, ic);
    std::printf(
        "[gpu-edits] edit %d: hits %llu, misses %llu, uploads so far %llu, max |gpu - cpu| %.5f\n",
        step, (unsigned long long)sg.hits, (unsigned long long)sg.misses,
        (unsigned long long)caster.poolStats().uploads, d);
    EXPECT_EQ(sg.misses, 0u) << "edit " << step;
    EXPECT_EQ(sg.hits, uint64_t(first.slots)) << "edit " << step;
    EXPECT_EQ(caster.poolStats().uploads, uploads) << "edit " << step;
    EXPECT_LE(d, 2.0 / 255.0) << "edit " << step;
  }
}

TEST(GpuFrameEdits, ImageLeftOnTheDeviceEqualsTheHostImage) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  auto file = afam_test::encodeMl(65, EncodingMode::Adaptive, 2, 4, 1e-3);
  const FrameSettings s = rampSettings(*file);
  Renderer renderer(file, RendererResources{}, s);
  std::unique_ptr<GpuCaster> owned =
      GpuCaster::create(size_t(64) << 20, 0, [](const std::string&) {});
  ASSERT_TRUE(owned);
  GpuCaster& caster = *owned;
  renderer.setCaster(std::move(owned));
  const Camera c = Camera::lookAt({0.9, 0.8, 0.7}, {0, 0, 0}, {0, 0, 1}, 60, 120, 90);
  FrameStats st;
  const ImageRGBA host = renderer.renderFrame(c, st);
  ASSERT_TRUE(st.cast.onGpu);
  ASSERT_FALSE(st.cast.imageOnDevice);

  const size_t floats = size_t(120) * 90 * 4;
  float* device = nullptr;
  ASSERT_EQ(cudaMalloc(reinterpret_cast<void**>(&device), floats * sizeof(float)), cudaSuccess);
  FrameTargets targets;
  targets.deviceRgba = device;
  targets.deviceRgbaFloats = floats;
  const ImageRGBA kept = renderer.renderFrame(c, st, targets);
  EXPECT_TRUE(st.cast.imageOnDevice);
  EXPECT_EQ(kept.width, 120);
  EXPECT_EQ(kept.height, 90);
  EXPECT_TRUE(kept.rgba.empty());
  EXPECT_EQ(caster.lastTimes().downloadMs, 0.0);
  EXPECT_EQ(st.cast.gpuDownloadMs, 0.0);
  std::vector<float> back(floats);
  ASSERT_EQ(cudaMemcpy(back.data(), device, floats * sizeof(float), cudaMemcpyDeviceToHost),
            cudaSuccess);
  size_t differing = 0, opaque = 0;
  for (size_t i = 0; i < floats; ++i) {
    differing += back[i] != host.rgba[i] ? 1 : 0;
    opaque += (i % 4 == 3 && host.rgba[i] > 0.01f) ? 1 : 0;
  }
  std::printf(
      "[gpu-target] 120x90 frame on the device: %zu of %zu floats differ from the host image, %zu "
      "pixels drawn\n",
      differing, floats, opaque);
  EXPECT_EQ(differing, 0u);
  EXPECT_GT(opaque, 1000u);

  // A buffer too small for the frame: the image comes to the host instead.
  targets.deviceRgbaFloats = floats / 2;
  const ImageRGBA fallback = renderer.renderFrame(c, st, targets);
  EXPECT_FALSE(st.cast.imageOnDevice);
  EXPECT_EQ(fallback.rgba, host.rgba);
  // A frame that names no device buffer after one that did: the host (nothing carries over).
  targets.deviceRgbaFloats = floats;
  (void)renderer.renderFrame(c, st, targets);
  EXPECT_TRUE(st.cast.imageOnDevice);
  const ImageRGBA next = renderer.renderFrame(c, st);
  EXPECT_FALSE(st.cast.imageOnDevice);
  EXPECT_EQ(next.rgba, host.rgba);
  ASSERT_EQ(cudaFree(device), cudaSuccess);
}

TEST(GpuFrameEdits, AFailingGpuHandsThisAndLaterFramesToTheCpuOnce) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  auto file = afam_test::encodeMl(65, EncodingMode::Adaptive, 2, 4, 1e-3);
  const FrameSettings s = rampSettings(*file);
  Renderer gpu(file, RendererResources{}, s), cpu(file, RendererResources{}, s);
  std::vector<std::string> reports;
  auto collect = [&](const FrameStats& frame) {
    reports.insert(reports.end(), frame.cast.messages.begin(), frame.cast.messages.end());
  };
  std::unique_ptr<GpuCaster> owned =
      GpuCaster::create(size_t(64) << 20, 0, [&](const std::string& m) { reports.push_back(m); });
  ASSERT_TRUE(owned);
  GpuCaster& caster = *owned;
  gpu.setCaster(std::move(owned));
  const Camera c = Camera::lookAt({0.9, 0.8, 0.7}, {0, 0, 0}, {0, 0, 1}, 60, 100, 80);
  FrameStats st;
  const ImageRGBA reference = cpu.renderFrame(c, st);
  (void)gpu.renderFrame(c, st);
  collect(st);
  EXPECT_FALSE(caster.failed());
  EXPECT_TRUE(st.cast.onGpu);
  const uint64_t casts = caster.poolStats().uploads;
  caster.gpu().setSimulatedFailure(true);
  FrameStats firstStats, secondStats;
  const ImageRGBA first = gpu.renderFrame(c, firstStats), second = gpu.renderFrame(c, secondStats);
  collect(firstStats);
  collect(secondStats);
  std::printf("[gpu-failure] %zu report(s): %s\n", reports.size(),
              reports.empty() ? "" : reports[0].c_str());
  EXPECT_TRUE(caster.failed());
  EXPECT_FALSE(caster.castsOnGpu());
  EXPECT_FALSE(firstStats.cast.onGpu);
  EXPECT_FALSE(secondStats.cast.onGpu);
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_NE(reports[0].find("the GPU failed"), std::string::npos);
  EXPECT_NE(reports[0].find("cudaErrorContextIsDestroyed"), std::string::npos);
  EXPECT_EQ(first.rgba, reference.rgba);   // the failing frame is drawn, by the CPU
  EXPECT_EQ(second.rgba, reference.rgba);  // and the next, without trying the GPU
  EXPECT_EQ(caster.poolStats().uploads, casts);
}

}  // namespace
}  // namespace afam
