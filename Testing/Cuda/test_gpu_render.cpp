// SPDX-License-Identifier: BSD-3-Clause
// GPU image == CPU reference image (same FrameView, same castRay) on Marschner-Lobb and two corpus
// volumes, degrees 1..3, shaded and unshaded; the GPU image is poisoned with NaN first so an
// unwritten pixel fails. Pool behaviour on the GPU over a replay. Skipped, with the reason, where
// no GPU is usable (CI).
#include <cuda_runtime_api.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <tuple>
#include <vector>

#include "afam/cuda/render/gpu_renderer.hpp"
#include "afam/render/cpu_raycaster.hpp"
#include "gpu_scene.hpp"

namespace afam::gputest {
namespace {

#define AFAM_SKIP_WITHOUT_GPU()                                        \
  do {                                                                 \
    std::string why;                                                   \
    if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why; \
  } while (0)

const EncodedVolume* encoded(const std::string& name, int degree) {
  static std::map<std::pair<std::string, int>, std::unique_ptr<EncodedVolume>> cache;
  auto& slot = cache[{name, degree}];
  if (slot) return slot.get();
  Volume v;
  if (name == "marschner_lobb") {
    v = marschnerLobbVolume(65);
  } else {
    const std::string dir = dataDirectory();
    if (name == "neghip")
      v = loadRawVolume(dir + "/volumes/neghip_66x66x66_uint8.raw", {66, 66, 66}, "uint8");
    else
      v = loadRawVolume(dir + "/volumes/ironProt_68x68x68_uint8.raw", {68, 68, 68}, "uint8");
  }
  slot = std::make_unique<EncodedVolume>(encodeVolume(v, 3, 8, degree, 0.75));
  return slot.get();
}

/// One frame of `e` seen by `camera`, cast by the CPU reference and by `gpu` (exact kernels).
struct BothImages {
  Frame frame;
  ImageRGBA cpu;
  std::vector<float> gpu;
  ImageDiff diff;
};
/// blendMode != 0: a projection; buildFrame's table holds opacities per 0.005 step (for
/// compositing) and a projection uses one opacity per ray, so it gets the per-unit opacities back
/// (alpha' = 1 - (1 - a)^200).
void renderOnBoth(GpuRenderer& gpu, const EncodedVolume& e, const Camera& camera, bool shaded,
                  BothImages& out, int blendMode = kBlendComposite) {
  FrameOptions options;
  options.shaded = shaded;
  options.sampleDistance = 0.005f;
  buildFrame(e, distanceBands(e.partition, camera), camera, options, out.frame);
  out.frame.view.blendMode = blendMode;
  if (blendMode != kBlendComposite)
    for (size_t i = 3; i < out.frame.tf.size(); i += 4)
      out.frame.tf[i] = 1.f - std::pow(1.f - out.frame.tf[i], 200.f);
  renderCpu(out.frame.view, out.cpu, 0);
  out.gpu.assign(out.cpu.rgba.size(), 0.f);
  gpu.render(out.frame.view, out.frame.keys.data(), out.gpu.data());
  out.diff = compareImages(out.cpu.rgba, out.gpu);
}

using Case = std::tuple<std::string, int, bool>;

class GpuMatchesCpu : public ::testing::TestWithParam<Case> {};

TEST_P(GpuMatchesCpu, ImagesAgree) {
  AFAM_SKIP_WITHOUT_GPU();
  const auto& [name, degree, shaded] = GetParam();
  const EncodedVolume* e = encoded(name, degree);
  ASSERT_NE(e, nullptr);
  GpuRenderer gpu(size_t(256) << 20);
  gpu.setPoisonOutput(true);
  // One view from outside (mixed LOD by distance bands) and one from inside the volume.
  const Pose poses[2] = {{2.6, 55.0, 30.0}, {1.25, 70.0, 200.0}};
  for (const Pose& pose : poses) {
    const Camera camera = Camera::fromPose(pose, 301, 256);  // awkward width on purpose
    BothImages both;
    renderOnBoth(gpu, *e, camera, shaded, both);
    const Frame& frame = both.frame;
    const ImageRGBA& cpu = both.cpu;
    const std::vector<float>& image = both.gpu;
    const ImageDiff& d = both.diff;
    std::printf(
        "[gpu-vs-cpu] %-14s p=%d %-8s pose(%.2f,%.0f,%.0f) slots=%d: max |diff| %d/255, "
        "%lld of %lld pixels differ, max float diff %.2e, unwritten %lld  (%s)\n",
        name.c_str(), degree, shaded ? "shaded" : "unshaded", pose.distance, pose.thetaDeg,
        pose.phiDeg, frame.view.slotCount, d.maxAbs8, (long long)d.differing, (long long)d.pixels,
        d.maxAbsFloat, (long long)d.nonFinite, gpu.lastKernelInfo().c_str());
    EXPECT_EQ(d.nonFinite, 0);
    EXPECT_LE(d.maxAbs8, 2);
    // The faster floating-point contracts, reported (the bar applies to the default, Exact).
    for (GpuFloatMode mode : {GpuFloatMode::Fma, GpuFloatMode::Fast}) {
      gpu.setFloatMode(mode);
      std::vector<float> other(image.size());
      gpu.render(frame.view, frame.keys.data(), other.data());
      const ImageDiff o = compareImages(cpu.rgba, other);
      std::printf(
          "[gpu-vs-cpu:%s] %-14s p=%d %-8s: max |diff| %d/255, %lld pixels differ, "
          "unwritten %lld\n",
          mode == GpuFloatMode::Fma ? "fma" : "fast", name.c_str(), degree,
          shaded ? "shaded" : "unshaded", o.maxAbs8, (long long)o.differing,
          (long long)o.nonFinite);
      EXPECT_EQ(o.nonFinite, 0);
    }
    gpu.setFloatMode(GpuFloatMode::Exact);
    // The image is not empty: the comparison means something.
    double alpha = 0;
    for (size_t i = 3; i < cpu.rgba.size(); i += 4) alpha += cpu.rgba[i];
    EXPECT_GT(alpha, 100.0);
  }
}

INSTANTIATE_TEST_SUITE_P(Volumes, GpuMatchesCpu,
                         ::testing::Combine(::testing::Values("marschner_lobb", "neghip",
                                                              "ironProt"),
                                            ::testing::Values(1, 2, 3), ::testing::Bool()),
                         [](const ::testing::TestParamInfo<Case>& param) {
                           return std::get<0>(param.param) + "_p" +
                                  std::to_string(std::get<1>(param.param)) +
                                  (std::get<2>(param.param) ? "_shaded" : "_unshaded");
                         });

// Cameras as the VTK mapper builds them: given in the world, mapped into the normalised frame of
// a non-cubic, rotated volume (non-orthonormal frame, per-ray step metric), perspective and
// parallel, off-centre (WindowCenter). Same FrameView on both sides: GPU == CPU.
TEST(GpuRenderer, MappedAndParallelCamerasMatchCpu) {
  AFAM_SKIP_WITHOUT_GPU();
  const EncodedVolume* e = encoded("marschner_lobb", 2);
  // World: the volume's box has half extents (2, 1, 0.5), rotated 30 degrees about z and moved
  // to (0.5, 0, 0): x' = S R^T (x - c).
  const double c30 = std::cos(0.5236), s30 = std::sin(0.5236);
  const std::array<double, 9> linear{c30 / 2, s30 / 2, 0, -s30, c30, 0, 0, 0, 2};
  const Vec3 offset{-0.5 * c30 / 2, 0.5 * s30, 0};
  GpuRenderer gpu(size_t(128) << 20);
  gpu.setPoisonOutput(true);
  for (bool parallel : {false, true}) {
    const Vec3 eye{5, 3.5, 4}, focal{0.5, 0, 0}, up{0, 0, 1};
    Camera world = parallel ? Camera::parallelLookAt(eye, focal, up, 1.6, 240, 200)
                            : Camera::lookAt(eye, focal, up, 30.0, 240, 200);
    world.centerX = 0.3 * world.tanHalfX;  // off-centre, as a screenshot tile
    world.centerY = -0.2 * world.tanHalfY;
    const Camera camera = world.mapped(linear, offset);
    ASSERT_TRUE(camera.hasStepMetric);
    for (bool shaded : {false, true}) {
      BothImages both;
      renderOnBoth(gpu, *e, camera, shaded, both);
      const Frame& frame = both.frame;
      const ImageRGBA& cpu = both.cpu;
      const ImageDiff& d = both.diff;
      std::printf(
          "[gpu-vs-cpu] mapped %-11s p=2 %-8s slots=%d: max |diff| %d/255, %lld of %lld "
          "pixels differ, unwritten %lld\n",
          parallel ? "parallel" : "perspective", shaded ? "shaded" : "unshaded",
          frame.view.slotCount, d.maxAbs8, (long long)d.differing, (long long)d.pixels,
          (long long)d.nonFinite);
      EXPECT_EQ(d.nonFinite, 0);
      EXPECT_LE(d.maxAbs8, 2);
      double alpha = 0;
      for (size_t i = 3; i < cpu.rgba.size(); i += 4) alpha += cpu.rgba[i];
      EXPECT_GT(alpha, 100.0);
    }
  }
}

// Maximum, minimum and average intensity projections: GPU == CPU, degree 2 and the generic path.
TEST(GpuRenderer, ProjectionsMatchCpu) {
  AFAM_SKIP_WITHOUT_GPU();
  const EncodedVolume* e = encoded("marschner_lobb", 2);
  const Camera camera = Camera::fromPose({2.4, 40.0, 120.0}, 200, 160);
  GpuRenderer gpu(size_t(64) << 20);
  gpu.setPoisonOutput(true);
  for (int mode : {kBlendMaximum, kBlendMinimum, kBlendAverage}) {
    for (bool specialise : {true, false}) {
      gpu.setDegreeSpecialisation(specialise);
      BothImages both;
      renderOnBoth(gpu, *e, camera, false, both, mode);
      const ImageRGBA& cpu = both.cpu;
      const ImageDiff& d = both.diff;
      std::printf(
          "[gpu-vs-cpu] projection mode=%d %s: max |diff| %d/255, %lld of %lld pixels "
          "differ, unwritten %lld  (%s)\n",
          mode, specialise ? "p=2" : "p=any", d.maxAbs8, (long long)d.differing,
          (long long)d.pixels, (long long)d.nonFinite, gpu.lastKernelInfo().c_str());
      EXPECT_EQ(d.nonFinite, 0);
      EXPECT_LE(d.maxAbs8, 2);
      // Not empty, so the comparison means something (the preset table makes the lowest values
      // transparent, so a minimum intensity image is nearly empty by design).
      double alpha = 0;
      for (size_t i = 3; i < cpu.rgba.size(); i += 4) alpha += cpu.rgba[i];
      if (mode != kBlendMinimum) {
        EXPECT_GT(alpha, 100.0);
      }
    }
  }
  gpu.setDegreeSpecialisation(true);
}

TEST(GpuRenderer, GenericDegreePathMatchesSpecialised) {
  AFAM_SKIP_WITHOUT_GPU();
  const EncodedVolume* e = encoded("marschner_lobb", 2);
  const Camera camera = Camera::fromPose({2.4, 40.0, 120.0}, 200, 160);
  Frame frame;
  buildFrame(*e, distanceBands(e->partition, camera), camera, FrameOptions{}, frame);
  GpuRenderer gpu(size_t(64) << 20);
  gpu.setPoisonOutput(true);
  std::vector<float> a(size_t(200) * 160 * 4), b(a.size());
  gpu.render(frame.view, frame.keys.data(), a.data());
  gpu.setDegreeSpecialisation(false);
  gpu.render(frame.view, frame.keys.data(), b.data());
  const ImageDiff d = compareImages(a, b);
  EXPECT_EQ(d.nonFinite, 0);
  EXPECT_LE(d.maxAbs8, 1);
  std::printf("[generic-vs-p2] max |diff| %d/255, %lld pixels differ, max float diff %.2e\n",
              d.maxAbs8, (long long)d.differing, d.maxAbsFloat);
}

TEST(GpuRenderer, MaxDistanceMatchesCpuAndHidesTheVolume) {
  // Per-pixel ray limits (opaque geometry, as the VTK mapper passes them): the left half of the
  // image is cut at the distance of the volume's centre, the top-right quarter in front of the
  // volume. GPU == CPU, the top-right quarter is empty, the left half dimmer than unlimited.
  AFAM_SKIP_WITHOUT_GPU();
  const EncodedVolume* e = encoded("marschner_lobb", 2);
  const int w = 201, h = 160;
  const Camera camera = Camera::fromPose({2.4, 40.0, 120.0}, w, h);
  Frame frame;
  buildFrame(*e, distanceBands(e->partition, camera), camera, FrameOptions{}, frame);
  std::vector<float> limit(size_t(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      limit[size_t(y) * w + size_t(x)] = x < w / 2 ? 2.4f : (y < h / 2 ? 0.5f : INFINITY);
  GpuRenderer gpu(size_t(64) << 20);
  gpu.setPoisonOutput(true);
  std::vector<float> full(size_t(w) * h * 4), cut(full.size());
  gpu.render(frame.view, frame.keys.data(), full.data());
  frame.view.maxDistance = limit.data();
  gpu.render(frame.view, frame.keys.data(), cut.data());
  ImageRGBA cpu;
  renderCpu(frame.view, cpu, 0);
  const ImageDiff d = compareImages(cpu.rgba, cut);
  double left = 0, leftFull = 0, hidden = 0, right = 0, rightFull = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = (size_t(y) * w + size_t(x)) * 4 + 3;
      if (x < w / 2) {
        left += cut[i];
        leftFull += full[i];
      } else if (y < h / 2) {
        hidden += cut[i];
      } else {
        right += cut[i];
        rightFull += full[i];
      }
    }
  std::printf(
      "[gpu-depth] max |diff| vs CPU %d/255, unwritten %lld; alpha left %.1f of %.1f, "
      "hidden %.3f, right %.1f of %.1f\n",
      d.maxAbs8, (long long)d.nonFinite, left, leftFull, hidden, right, rightFull);
  EXPECT_EQ(d.nonFinite, 0);
  EXPECT_LE(d.maxAbs8, 2);
  EXPECT_EQ(hidden, 0.0);
  EXPECT_GT(leftFull, 10.0);
  EXPECT_LT(left, 0.9 * leftFull);
  EXPECT_GT(left, 0.05 * leftFull);
  EXPECT_NEAR(right, rightFull, 1e-3 * rightFull + 1e-6);
}

TEST(GpuDsBaseline, RawBlocksMatchCpuAndTexturePathWritesEveryPixel) {
  AFAM_SKIP_WITHOUT_GPU();
  const EncodedVolume e = rawBlocks(marschnerLobbVolume(65), 3, 8);
  GpuRenderer gpu(size_t(64) << 20);
  gpu.setPoisonOutput(true);
  for (bool shaded : {false, true}) {
    const Camera camera = Camera::fromPose({2.6, 55.0, 30.0}, 301, 256);
    Frame frame;
    FrameOptions options;
    options.shaded = shaded;
    buildFrame(e, distanceBands(e.partition, camera), camera, options, frame);
    ImageRGBA cpu;
    renderCpu(frame.view, cpu, 0);
    std::vector<float> image(cpu.rgba.size());
    gpu.setDsTextures(false);
    gpu.render(frame.view, frame.keys.data(), image.data());
    const ImageDiff d = compareImages(cpu.rgba, image);
    gpu.setDsTextures(true);
    gpu.render(frame.view, frame.keys.data(), image.data());
    const std::string info = gpu.lastKernelInfo();
    const ImageDiff t = compareImages(cpu.rgba, image);
    std::printf(
        "[ds] %s: castRay raw slots vs CPU max |diff| %d/255 (%lld px); 3D textures vs "
        "CPU max |diff| %d/255 (%lld px differ, hardware 8-bit filter weights) (%s)\n",
        shaded ? "shaded" : "unshaded", d.maxAbs8, (long long)d.differing, t.maxAbs8,
        (long long)t.differing, info.c_str());
    EXPECT_EQ(d.nonFinite, 0);
    EXPECT_LE(d.maxAbs8, 2);
    EXPECT_EQ(t.nonFinite, 0);
  }
}

TEST(GpuModelPool, ReplayUploadsMatchLedgerAndStayUnderBudget) {
  AFAM_SKIP_WITHOUT_GPU();
  const EncodedVolume* e = encoded("marschner_lobb", 2);
  const std::vector<Pose> all = explorationPoses("user_1.dat");
  std::vector<Pose> poses;
  for (size_t i = 0; i < all.size(); i += 10) poses.push_back(all[i]);
  // Budget: 60% of all models of all levels, so the replay must evict.
  size_t total = 0;
  for (const auto& level : e->models)
    for (const FitResult& m : level) total += ((m.control.size() * 4 + 255) / 256) * 256;
  const size_t budget = total * 6 / 10;
  GpuRenderer gpu(budget);
  PoolLedger reference(budget, 256);
  uint64_t expectedUploads = 0;
  Frame frame;
  std::vector<float> image;
  for (const Pose& pose : poses) {
    const Camera camera = Camera::fromPose(pose, 64, 64);
    buildFrame(*e, distanceBands(e->partition, camera), camera, FrameOptions{}, frame);
    reference.beginFrame();
    for (size_t s = 0; s < frame.slots.size(); ++s)
      reference.acquire(frame.keys[s], GpuRenderer::slotFloats(frame.slots[s]) * 4);
    image.resize(size_t(64) * 64 * 4);
    GpuFrameTimes t;
    gpu.render(frame.view, frame.keys.data(), image.data(), &t);
    expectedUploads = reference.stats().uploads;
    ASSERT_EQ(gpu.pool().stats().uploads, expectedUploads);
    ASSERT_EQ(gpu.pool().stats().evictions, reference.stats().evictions);
    ASSERT_LE(gpu.pool().stats().residentBytes, budget);
    // The same frame again uploads nothing.
    gpu.render(frame.view, frame.keys.data(), image.data(), &t);
    ASSERT_EQ(t.modelsUploaded, 0u);
  }
  const PoolStats& s = gpu.pool().stats();
  std::printf(
      "[pool] %zu frames, budget %zu B (60%% of %zu): %llu uploads, %llu hits, %llu "
      "evictions, %.1f MB uploaded, peak resident %zu B\n",
      poses.size(), budget, total, (unsigned long long)s.uploads, (unsigned long long)s.hits,
      (unsigned long long)s.evictions, double(s.bytesUploaded) / 1e6, s.peakResidentBytes);
  EXPECT_LE(s.peakResidentBytes, budget);
  EXPECT_GT(s.evictions, 0u);
}

TEST(GpuModelPool, OutOfBudgetIsRecoverable) {
  AFAM_SKIP_WITHOUT_GPU();
  const EncodedVolume* e = encoded("marschner_lobb", 2);
  const Camera camera = Camera::fromPose({2.6, 55.0, 30.0}, 64, 64);
  Frame big, small;
  buildFrame(*e, wholeLevel(e->partition, 2), camera, FrameOptions{}, big);
  buildFrame(*e, wholeLevel(e->partition, 0), camera, FrameOptions{}, small);
  size_t smallBytes = 0;
  for (const FrameSlot& s : small.slots)
    smallBytes += ((GpuRenderer::slotFloats(s) * 4 + 255) / 256) * 256;
  GpuRenderer gpu(smallBytes * 2);
  std::vector<float> image(size_t(64) * 64 * 4);
  EXPECT_THROW(gpu.render(big.view, big.keys.data(), image.data()), GpuOutOfMemory);
  // The renderer is still usable for a frame that fits.
  EXPECT_NO_THROW(gpu.render(small.view, small.keys.data(), image.data()));
  // A device allocation far beyond the card is an error, not a crash.
  EXPECT_THROW(GpuRenderer(size_t(1) << 50), GpuOutOfMemory);
}

TEST(GpuModelPool, AFrameThatStoppedShortDecodesItsModelsBeforeTheirRoomIsReused) {
  AFAM_SKIP_WITHOUT_GPU();
  const size_t capacity = 64 * 1024;
  GpuModelPool pool(capacity);
  // A frame places a model the GPU decodes (a constant, queued), then one that cannot fit.
  const float seven = 7.f;
  GpuDecodeJob job;
  job.kind = GpuDecodeKind::Constant;
  job.ncp[0] = job.ncp[1] = job.ncp[2] = 16;  // 16 KiB of floats
  pool.beginFrame();
  pool.acquireStored(1, reinterpret_cast<const uint8_t*>(&seven), sizeof seven, 16 * 1024, job);
  const std::vector<float> threes(capacity / sizeof(float), 3.f);
  EXPECT_THROW(pool.acquire(2, threes.data(), capacity), GpuOutOfMemory);
  // The next frame's model takes the whole pool, the room of the first one too: its bytes must
  // not be overwritten by the first one's decoding, left over from the frame that stopped.
  pool.beginFrame();
  const size_t offset = pool.acquire(3, threes.data(), capacity);
  pool.flush();
  ASSERT_EQ(cudaStreamSynchronize(static_cast<cudaStream_t>(pool.stream())), cudaSuccess);
  std::vector<float> back(threes.size(), 0.f);
  ASSERT_EQ(cudaMemcpy(back.data(), static_cast<const char*>(pool.arena()) + offset, capacity,
                       cudaMemcpyDeviceToHost),
            cudaSuccess);
  size_t wrong = 0;
  for (float v : back) wrong += v != 3.f;
  EXPECT_EQ(wrong, 0u);
  EXPECT_TRUE(pool.takeDecodeFailures().empty());
}

}  // namespace
}  // namespace afam::gputest
