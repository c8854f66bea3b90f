// SPDX-License-Identifier: BSD-3-Clause
// Sort-last rendering on the CPU: each rank draws its box of the frame (clipFrameToBox), and the
// ranks' images composited in visibility order (rank_images.hpp) equal the image of one box, for
// 2, 3 and 4 ranks, composite and maximum-intensity blending, cameras outside and inside the
// volume, on a cubic volume (Marschner-Lobb) and a non-cubic one (the skewed blob).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "afam/base/errors.hpp"
#include "afam/ranks/rank_boxes.hpp"
#include "afam/ranks/rank_images.hpp"
#include "afam/render/frame_caster.hpp"
#include "afam/render/prepared_frame.hpp"
#include "render_test_util.hpp"
#include "skewed_blob.hpp"

using namespace afam;

namespace {

constexpr float kBound = 2.f / 255.f;

struct Scene {
  std::shared_ptr<const AfamFile> file;
  const char* name;
};

/// Options of every frame: a ramp whose premultiplied colour and opacity grow with the value
/// (maximum intensity composites exactly), shading on, 2 threads.
RenderOptions options(const AfamFile& file, int blendMode, int forceLevel) {
  RenderOptions o;
  o.threads = 2;
  o.loadThreads = 2;
  o.blendMode = blendMode;
  o.lod.forceLevel = forceLevel;
  const double lo = file.header().valueMin, hi = file.header().valueMax;
  o.transferFunction = afam_test::ramp(lo, hi, lo + 0.1 * (hi - lo), 0.5);
  o.hasTransferFunction = true;
  return o;
}

/// What one comparison measured: the largest channel difference, and how many ranks drew
/// something (an opacity above 1/255 somewhere).
struct Compared {
  float maxDiff = 0;
  int ranksDrawing = 0;
};

/// Draws `camera`'s frame of the whole volume and of each of `ranks` boxes, composites the boxes'
/// images and compares.
Compared compareRanks(const std::shared_ptr<const AfamFile>& file, const Camera& camera,
                      const RenderOptions& o, int ranks, float termination) {
  Renderer renderer(file, o);
  PreparedFrame whole;
  FrameStats stats;
  renderer.prepare(camera, whole, stats);
  whole.view.terminationOpacity = termination;
  CpuCaster caster(2);
  ImageRGBA one;
  caster.cast(whole, {}, one);
  const RankSplit split = RankSplit::ofFile(*file, ranks);
  std::vector<ImageRGBA> images(static_cast<size_t>(ranks));
  Compared c;
  for (int r = 0; r < ranks; ++r) {
    PreparedFrame part = whole;
    clipFrameToBox(part, split.boxes()[size_t(r)]);
    caster.cast(part, {}, images[size_t(r)]);
    c.ranksDrawing += afam_test::largestAlpha(images[size_t(r)]) > 1.f / 255.f ? 1 : 0;
  }
  const std::vector<int> order = split.visibilityOrder(whole.view.camera, whole.view.boxLo,
                                                       whole.view.boxHi, file->partition().dims());
  c.maxDiff = afam_test::maxDifference(compositeRankImages(images, order, o.blendMode), one);
  return c;
}

std::vector<Scene> scenes() {
  return {{afam_test::encodeMl(65, EncodingMode::Adaptive, 3, 4, 1e-3), "ML 65^3"},
          {afam_test::encodeSkewedBlob(), "blob 81x57x41"}};
}

/// Cameras outside and inside the volume, looking at the blob's corner.
std::vector<std::pair<Camera, const char*>> cameras() {
  return {
      {Camera::lookAt({1.7, 1.2, 1.3}, {0.1, 0.0, -0.1}, {0, 0, 1}, 40, 64, 56), "outside"},
      {Camera::lookAt({-0.3, -0.2, 0.25}, {0.44, 0.36, -0.4}, {0, 0, 1}, 70, 64, 56), "inside"}};
}

/// The largest difference over every scene, camera outside and inside, and 2, 3 and 4 ranks
/// (LOD by distance; and every block at the coarsest level, whose blocks span several boxes, with
/// 3 ranks), each measured printed; expects every rank count to have at least 2 ranks drawing.
float largestDifference(int blendMode, float termination, bool all = true) {
  float largest = 0;
  for (const Scene& s : scenes())
    for (const auto& [camera, where] : cameras())
      for (const auto& [level, ranks] : {std::pair{-1, 2}, {-1, 3}, {-1, 4}, {0, 3}}) {
        if (!all && ranks != 4) continue;
        const RenderOptions o = options(*s.file, blendMode, level);
        const Compared c = compareRanks(s.file, camera, o, ranks, termination);
        std::printf(
            "%s, %s, termination %.4f, camera %s, %s, %d ranks: max difference "
            "%.4f/255, %d ranks drawing\n",
            s.name, blendMode == kBlendComposite ? "composite" : "maximum", termination, where,
            level < 0 ? "LOD by distance" : "coarsest level", ranks, c.maxDiff * 255.f,
            c.ranksDrawing);
        EXPECT_GE(c.ranksDrawing, 2) << s.name << " " << where << " " << ranks << " ranks";
        largest = std::max(largest, c.maxDiff);
      }
  return largest;
}

}  // namespace

// Early ray termination at 1 - 1/255 (VTK's threshold): a ray's light after its stop is below
// 1/255, so the ranks (each stopping on its own) add less than that to the one-box image.
TEST(BoxFrames, RanksCompositeTheImageOfOneBox) {
  EXPECT_LE(largestDifference(kBlendComposite, 1.f - 1.f / 255.f), kBound);
}

TEST(BoxFrames, RanksMaximumIntensityIsTheImageOfOneBox) {
  EXPECT_LE(largestDifference(kBlendMaximum, 0.95f), kBound);
}

// No early termination: every sample is drawn by exactly one rank with the one-box ray's
// position, value and weight, so only the rounding of "over" differs.
TEST(BoxFrames, WithoutEarlyTerminationOnlyRoundingDiffers) {
  EXPECT_LE(largestDifference(kBlendComposite, 1.f, false), 1e-5f);
}

// At a termination of 0.95 (the renderer's default before kTerminationOpacity) the ranks add the
// light the one-box ray left out after its stop: what is left of its transmittance, 1 - 0.95, times
// the brightest a shaded sample can be (the ramp's colour, at most 1, lit by ambient + diffuse
// plus the white specular highlight: 1.2 by default), which the 2/255 bar does not allow. (ML 65^3
// seen from inside by 4 ranks: 14.3/255, over the unshaded 12.75/255.)
TEST(BoxFrames, AtTheDefaultTerminationRanksAddWhatTheOneBoxRayLeftOut) {
  const FrameView defaults;
  const float brightest = defaults.ambient + defaults.diffuse + defaults.specular;
  const float d = largestDifference(kBlendComposite, 0.95f, false);
  EXPECT_LE(d, 0.05f * brightest + 1e-5f);
  EXPECT_GT(d, kBound);
}

TEST(BoxFrames, BadBoxesAndImagesAreRefused) {
  const auto file = afam_test::encodeSkewedBlob();
  Renderer renderer(file, options(*file, kBlendComposite, -1));
  PreparedFrame frame;
  renderer.prepareEmpty(cameras()[0].first, frame);
  EXPECT_THROW(clipFrameToBox(frame, CellBox{{0, 0, 0}, {9, 8, 8}}), InvalidArgument);
  ImageRGBA a, b;
  a.resize(4, 3);
  b.resize(3, 4);
  EXPECT_THROW(compositeRankImages({a, b}, {0, 1}, kBlendComposite), InvalidArgument);
  EXPECT_THROW(compositeRankImages({a, a}, {0, 0}, kBlendComposite), InvalidArgument);
  EXPECT_THROW(compositeRankImages({a, a}, {1}, kBlendComposite), InvalidArgument);
  EXPECT_THROW(compositeRankImages({a, a}, {0, 1}, kBlendAverage), InvalidArgument);
  EXPECT_THROW(compositeRankImages({}, {}, kBlendMaximum), InvalidArgument);
}
