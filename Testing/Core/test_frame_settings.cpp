// SPDX-License-Identifier: BSD-3-Clause
// Per-frame settings: a Renderer keeps its cache and prefetcher across edits of the transfer
// function, shading, blend mode, sample distance and LOD (only models that become visible are
// read), and unusable settings are refused by the Renderer and replaced, with a warning naming
// the setting and the kept value, by acceptFrameSettings.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>

#include "afam/base/errors.hpp"
#include "afam/render/frame_settings.hpp"
#include "afam/render/renderer.hpp"
#include "render_test_util.hpp"

using namespace afam;

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

using afam_test::ramp;

std::set<int64_t> visibleEntries(const Renderer& r, const Camera& c) {
  std::set<int64_t> s;
  for (const BlockRef& b : r.select(c).visible) s.insert(b.entry);
  return s;
}

}  // namespace

TEST(FrameSettings, EditsKeepTheCacheAndReadOnlyNewlyVisibleModels) {
  auto file = afam_test::encodeMl(65, EncodingMode::Adaptive, 3, 4, 1e-2);
  const double lo = file->header().valueMin, hi = file->header().valueMax;
  RendererResources resources;
  resources.threads = 2;
  resources.cache = CacheBudget{};
  resources.prefetch = "linear";
  FrameSettings s;
  s.hasTransferFunction = true;
  s.transferFunction = ramp(lo, hi, lo + 0.7 * (hi - lo), 0.1);
  s.lod.bandWidth = 100;  // no distance reaches a coarser band: every block is finest
  s.sampleDistance = 0.02f;
  Renderer r(file, resources, s);
  const Camera c = Camera::lookAt({1.2, 1.0, 0.8}, {0, 0, 0}, {0, 0, 1}, 50, 48, 48);
  FrameStats first;
  r.renderFrame(c, first);
  ASSERT_GT(first.misses, 0u);
  const std::set<int64_t> before = visibleEntries(r, c);

  // Colour, shading, sample distance, lighting: the same blocks, all from the cache.
  FrameSettings edited = s;
  for (int step = 0; step < 4; ++step) {
    if (step == 0) edited.transferFunction.colors[0].r = 0.9;
    if (step == 1) edited.shading = false;
    if (step == 2) edited.sampleDistance = 0.013f;
    if (step == 3) edited.ambient = 0.5f;
    FrameStats st;
    r.renderFrame(c, edited, st);
    EXPECT_EQ(st.misses, 0u) << "step " << step;
    EXPECT_EQ(st.bytesRead, 0u) << "step " << step;
    EXPECT_EQ(st.hits, before.size()) << "step " << step;
  }
  // An opacity edit that makes more of the range visible: TF culling follows the new table at
  // once; exactly the newly visible models are read, none of the others again.
  edited.transferFunction = ramp(lo, hi, lo + 0.2 * (hi - lo), 0.9);
  r.setFrameSettings(edited);
  const std::set<int64_t> after = visibleEntries(r, c);
  size_t added = 0;
  for (int64_t e : after) added += before.count(e) ? 0 : 1;
  std::printf("visible before %zu, after %zu, newly visible %zu\n", before.size(), after.size(),
              added);
  ASSERT_GT(added, 0u) << "the wider ramp should uncull blocks";
  FrameStats wider;
  r.renderFrame(c, wider);
  EXPECT_EQ(wider.misses, added);
  EXPECT_EQ(wider.hits, after.size() - added);
  EXPECT_EQ(r.settings().transferFunction.opacities[1].value, lo + 0.2 * (hi - lo));
}

TEST(FrameSettings, RendererRefusesUnusableSettingsAndKeepsItsOwn) {
  auto file = afam_test::encodeMl(33, EncodingMode::Adaptive, 2, 2, 1e-2);
  Renderer r(file, RendererResources{});
  const float kept = r.settings().sampleDistance;
  for (float d : {0.f, -0.01f, float(kNaN)}) {
    FrameSettings bad;
    bad.sampleDistance = d;
    EXPECT_THROW(r.setFrameSettings(bad), InvalidArgument) << d;
  }
  FrameSettings empty;
  empty.hasTransferFunction = true;  // and no points
  EXPECT_THROW(r.setFrameSettings(empty), InvalidArgument);
  EXPECT_EQ(r.settings().sampleDistance, kept);
  EXPECT_FALSE(r.settings().transferFunction.colors.empty());  // still the preset
}

TEST(FrameSettings, AcceptNamesEachUnusableSettingAndKeepsTheLastGoodValue) {
  FrameSettings kept;
  kept.sampleDistance = 0.004f;
  kept.hasTransferFunction = true;
  kept.transferFunction = ramp(0, 1, 0.5, 0.2);
  {
    FrameSettings wanted = kept;
    wanted.sampleDistance = 0;
    wanted.shading = false;  // a good edit in the same request goes through
    std::vector<std::string> warnings;
    const FrameSettings got = acceptFrameSettings(wanted, kept, warnings);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("sample distance 0 "), std::string::npos) << warnings[0];
    EXPECT_NE(warnings[0].find("keeping 0.004"), std::string::npos) << warnings[0];
    EXPECT_EQ(got.sampleDistance, 0.004f);
    EXPECT_FALSE(got.shading);
    EXPECT_TRUE(frameSettingsProblem(got).empty());
  }
  {
    FrameSettings wanted = kept;
    wanted.sampleDistance = -2;
    wanted.transferFunction.opacities.clear();
    std::vector<std::string> warnings;
    const FrameSettings got = acceptFrameSettings(wanted, kept, warnings);
    ASSERT_EQ(warnings.size(), 2u);
    EXPECT_NE(warnings[0].find("sample distance -2 "), std::string::npos) << warnings[0];
    EXPECT_NE(warnings[1].find("opacity transfer function has no points"), std::string::npos);
    EXPECT_NE(warnings[1].find("2 colour and 3 opacity points"), std::string::npos) << warnings[1];
    EXPECT_EQ(got.transferFunction.opacities.size(), 3u);
  }
  {
    FrameSettings wanted = kept;
    wanted.transferFunction.colors[1].g = kNaN;
    std::vector<std::string> warnings;
    const FrameSettings got = acceptFrameSettings(wanted, kept, warnings);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("colour point 1"), std::string::npos) << warnings[0];
    EXPECT_EQ(got.transferFunction.colors[1].g, 0.9);
  }
  {
    FrameSettings wanted = kept;
    wanted.transferFunction.opacities[0].value = kNaN;
    wanted.transferFunction.referenceDistance = -1;
    std::vector<std::string> warnings;
    acceptFrameSettings(wanted, kept, warnings);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("opacity point 0 (value nan"), std::string::npos) << warnings[0];
  }
  {
    FrameSettings wanted = kept;
    wanted.transferFunction.referenceDistance = 0;
    wanted.lod.pixelBudget = kNaN;
    wanted.blendMode = 7;
    std::vector<std::string> warnings;
    const FrameSettings got = acceptFrameSettings(wanted, kept, warnings);
    ASSERT_EQ(warnings.size(), 3u);
    EXPECT_NE(warnings[0].find("blend mode 7"), std::string::npos) << warnings[0];
    EXPECT_NE(warnings[1].find("LOD pixel budget nan"), std::string::npos) << warnings[1];
    EXPECT_NE(warnings[2].find("opacity unit distance 0 "), std::string::npos) << warnings[2];
    EXPECT_EQ(got.blendMode, kBlendComposite);
    EXPECT_EQ(got.lod.pixelBudget, 1.0);
    EXPECT_EQ(got.transferFunction.referenceDistance, 0.02);
  }
  {  // with no good transfer function yet, the file's default is kept, and said so
    FrameSettings first;
    FrameSettings wanted;
    wanted.hasTransferFunction = true;
    std::vector<std::string> warnings;
    const FrameSettings got = acceptFrameSettings(wanted, first, warnings);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("colour transfer function has no points"), std::string::npos);
    EXPECT_NE(warnings[0].find("the file's default"), std::string::npos) << warnings[0];
    EXPECT_FALSE(got.hasTransferFunction);
  }
}

TEST(FrameSettings, PointsGivenHighToLowAreTheSameFunction) {
  // An inverted range (points listed from the top of the range down, as a reversed colour map
  // arrives) is no error: the points are sorted, and the table is the one of the sorted points.
  const TransferFunction sorted = ramp(-2.0, 5.0, 1.0, 0.3);
  TransferFunction inverted = sorted;
  std::reverse(inverted.colors.begin(), inverted.colors.end());
  std::reverse(inverted.opacities.begin(), inverted.opacities.end());
  EXPECT_TRUE(transferFunctionProblem(inverted).empty());
  EXPECT_EQ(inverted.table(256, -2.0, 5.0), sorted.table(256, -2.0, 5.0));
  FrameSettings s;
  s.hasTransferFunction = true;
  s.transferFunction = inverted;
  std::vector<std::string> warnings;
  const FrameSettings got = acceptFrameSettings(s, FrameSettings{}, warnings);
  EXPECT_TRUE(warnings.empty());
  EXPECT_TRUE(got.hasTransferFunction);
}
