// SPDX-License-Identifier: BSD-3-Clause
// No sample is classified outside the value range the source had: a step function (0 | 100, a
// sharp edge the splines overshoot) encoded at 1e-2, drawn by the CPU ray caster through a
// sampler that records every value castRayWith classifies.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <vector>

#include "afam/encode/encoder.hpp"
#include "afam/render/cpu_raycaster.hpp"
#include "afam/render/renderer.hpp"
#include "render_test_util.hpp"

using namespace afam;

namespace {

constexpr int kN = 48;

/// 0 below x = 20.5, 100 above: one sharp edge across the volume, encoded once per process.
std::shared_ptr<const AfamFile> stepFile() {
  const std::string path = afam_test::tempPath("step_edge");
  if (::access(path.c_str(), R_OK) != 0) {
    std::vector<float> v(size_t(kN) * kN * kN);
    for (size_t i = 0; i < v.size(); ++i) v[i] = int(i % kN) > 20 ? 100.f : 0.f;
    ArraySource src(v.data(), {kN, kN, kN});
    EncoderOptions o;
    o.levels = 2;
    o.blocksPerAxis = 4;
    o.errorBound = 1e-2;
    o.threads = 2;
    encodeVolume(src, o, path);
  }
  return AfamFile::open(path);
}

/// The values castRayWith classifies: the model sampler's, counted against [lo, hi] and the
/// sampled slot's own range (one thread: renderCpuWith(..., 1)).
struct RecordingSampler {
  mutable double lowest = 1e30, highest = -1e30;
  mutable long long samples = 0, outsideSlot = 0;
  template <bool G>
  bool sample(const FrameView& f, const float* p, float& value, float* g) const {
    if (!ModelSampler{}.sample<G>(f, p, value, g)) return false;
    if (value != value) return true;  // missing: never classified as a value
    ++samples;
    lowest = std::min(lowest, double(value));
    highest = std::max(highest, double(value));
    float x[3];
    const FrameSlot& s = f.slots[locateSample(f, p, x)];
    outsideSlot += value < s.valueMin || value > s.valueMax;
    return true;
  }
};

RecordingSampler castFrame(const PreparedFrame& frame) {
  RecordingSampler rec;
  ImageRGBA image;
  renderCpuWith(frame.view, rec, image, 1);
  return rec;
}

}  // namespace

TEST(SourceRange, NoSampleOfASharpEdgeIsClassifiedOutsideTheSourcesRange) {
  auto file = stepFile();
  ASSERT_EQ(file->header().valueMin, 0.0);
  ASSERT_EQ(file->header().valueMax, 100.0);
  RenderOptions o;
  o.threads = 1;
  o.sampleDistance = 0.005f;
  o.lod.forceLevel = file->header().levels - 1;  // the finest models: the edge at its sharpest
  Renderer r(file, o);
  // Across the edge (x axis), through the whole volume.
  const Camera c = Camera::parallelLookAt({0, 3, 0.2}, {0, 0, 0}, {0, 0, 1}, 1.1, 64, 64);
  PreparedFrame frame;
  FrameStats st;
  r.prepare(c, frame, st);
  // Without the slots' ranges (FrameSlot's defaults clamp nothing) the splines overshoot: the
  // check below can fail.
  PreparedFrame unclamped = frame;
  for (FrameSlot& s : unclamped.slots) s.valueMin = -3.0e38f, s.valueMax = 3.0e38f;
  unclamped.bind();
  const RecordingSampler raw = castFrame(unclamped);
  const RecordingSampler drawn = castFrame(frame);
  std::printf("[source range] %lld samples: unclamped %.3f .. %.3f, drawn %.3f .. %.3f\n",
              drawn.samples, raw.lowest, raw.highest, drawn.lowest, drawn.highest);
  ASSERT_GT(drawn.samples, 100000);
  EXPECT_LT(raw.lowest, -0.5) << "the spline does not overshoot below the edge";
  EXPECT_GT(raw.highest, 100.5) << "the spline does not overshoot above the edge";
  EXPECT_GE(drawn.lowest, 0.0);
  EXPECT_LE(drawn.highest, 100.0);
  EXPECT_EQ(drawn.outsideSlot, 0);
}
