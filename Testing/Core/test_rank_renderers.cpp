// SPDX-License-Identifier: BSD-3-Clause
// Sort-last rendering with whole renderers: N Renderers of one file, each restricted to its rank's
// box (RendererResources::box, rankBox), draw a short camera path; their images composited in
// visibility order equal the unrestricted renderer's, each rank reads about 1/N of its bytes, and
// every rank draws. The head MRI (48 x 62 x 42, a real scan), 3 levels of 8 finest blocks an axis.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "afam/base/errors.hpp"
#include "afam/encode/encoder.hpp"
#include "afam/ranks/rank_boxes.hpp"
#include "afam/ranks/rank_images.hpp"
#include "afam/render/renderer.hpp"
#include "head_mri.hpp"
#include "render_test_util.hpp"

using namespace afam;

namespace {

constexpr float kBound = 2.f / 255.f;
/// What a rank may read of the one-rank bytes, times N (issue 43's bar): 1/N and the coarser
/// blocks that span its box's faces, which every rank that meets them reads.
constexpr double kShareTimesRanks = 1.3;

std::shared_ptr<const AfamFile> headFile() {
  const std::string path = afam_test::tempPath("rank_renderers_head");
  if (::access(path.c_str(), R_OK) != 0) {
    const std::vector<float> v = afam_test::headMri();
    ArraySource src(v.data(), {48, 62, 42});
    EncoderOptions o;
    o.levels = 3;
    o.blocksPerAxis = 8;
    o.errorBound = 1e-2;
    o.relativeBound = true;
    o.threads = 2;
    encodeVolume(src, o, path);
  }
  return AfamFile::open(path);
}

/// The renderer of every rank (and of one): the ramp from a tenth of the range, shading on,
/// every block it reads kept (so bytes read are the blocks the path needs, once).
RenderOptions options(const AfamFile& file) {
  RenderOptions o;
  o.threads = 2;
  o.loadThreads = 2;
  o.cache = CacheBudget{0, 0};
  const double lo = file.header().valueMin, hi = file.header().valueMax;
  o.transferFunction = afam_test::ramp(lo, hi, lo + 0.1 * (hi - lo), 0.5);
  o.hasTransferFunction = true;
  return o;
}

/// A recorded-style path: the camera swings round the head and comes closer, the last view from
/// inside the volume.
std::vector<Camera> cameraPath() {
  std::vector<Camera> path;
  for (const auto& eye : {Vec3{2.6, 1.2, 0.9}, Vec3{1.6, 2.2, 0.6}, Vec3{0.4, 2.0, 1.1},
                          Vec3{-0.9, 1.2, 0.7}, Vec3{-0.35, 0.3, 0.2}})
    path.push_back(Camera::lookAt(eye, {0.0, 0.0, 0.0}, {0, 0, 1}, 45, 72, 60));
  return path;
}

/// What N ranks did over the path: the largest difference of their composite from the one-rank
/// image, the bytes each read, and how many views each drew something in.
struct RankRun {
  float maxDiff = 0;
  std::vector<uint64_t> bytes;
  std::vector<int> viewsDrawn;
};

RankRun runRanks(const std::shared_ptr<const AfamFile>& file, int ranks,
                 const std::vector<ImageRGBA>& oneRank) {
  const RankSplit split = RankSplit::ofFile(*file, ranks);
  std::vector<std::unique_ptr<Renderer>> renderers;
  for (int r = 0; r < ranks; ++r) {
    RenderOptions o = options(*file);
    o.box = rankBox(*file, r, ranks);
    renderers.push_back(std::make_unique<Renderer>(file, o));
  }
  RankRun run{0, std::vector<uint64_t>(size_t(ranks), 0), std::vector<int>(size_t(ranks), 0)};
  const std::vector<Camera> path = cameraPath();
  for (size_t v = 0; v < path.size(); ++v) {
    std::vector<ImageRGBA> images;
    for (int r = 0; r < ranks; ++r) {
      FrameStats st;
      images.push_back(renderers[size_t(r)]->renderFrame(path[v], st));
      run.bytes[size_t(r)] += st.bytesRead;
      run.viewsDrawn[size_t(r)] += afam_test::largestAlpha(images.back()) > 1.f / 255.f ? 1 : 0;
    }
    const float lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
    const std::vector<int> order =
        split.visibilityOrder(path[v].toRayCamera(), lo, hi, file->partition().dims());
    run.maxDiff = std::max(
        run.maxDiff,
        afam_test::maxDifference(compositeRankImages(images, order, kBlendComposite), oneRank[v]));
  }
  return run;
}

}  // namespace

TEST(RankRenderers, RanksDrawTheOneRankImageAndReadTheirShare) {
  const auto file = headFile();
  Renderer one(file, options(*file));
  std::vector<ImageRGBA> oneRank;
  uint64_t oneBytes = 0;
  for (const Camera& c : cameraPath()) {
    FrameStats st;
    oneRank.push_back(one.renderFrame(c, st));
    oneBytes += st.bytesRead;
  }
  ASSERT_GT(oneBytes, 0u);
  for (int ranks : {2, 3, 4}) {
    const RankRun run = runRanks(file, ranks, oneRank);
    std::printf("%d ranks: max difference %.3f/255; bytes read of the one rank's %llu:", ranks,
                run.maxDiff * 255.f, (unsigned long long)oneBytes);
    for (int r = 0; r < ranks; ++r)
      std::printf(" %.3f", double(run.bytes[size_t(r)]) / double(oneBytes));
    std::printf(" (1/N %.3f)\n", 1.0 / ranks);
    EXPECT_LE(run.maxDiff, kBound) << ranks << " ranks";
    for (int r = 0; r < ranks; ++r) {
      EXPECT_LE(double(run.bytes[size_t(r)]), kShareTimesRanks / ranks * double(oneBytes))
          << "rank " << r << " of " << ranks;
      EXPECT_GE(run.viewsDrawn[size_t(r)], 1) << "rank " << r << " of " << ranks;
    }
  }
}

// A box beyond the volume's cells, or an empty box, draws a transparent image and reads nothing.
TEST(RankRenderers, ABoxWithoutCellsDrawsNothingAndReadsNothing) {
  const auto file = headFile();
  for (const CellBox& box : {CellBox{{9, 9, 9}, {12, 12, 12}}, CellBox{{2, 2, 2}, {2, 5, 5}},
                             CellBox{{-4, 0, 0}, {0, 8, 8}}}) {
    RenderOptions o = options(*file);
    o.box = box;
    o.missBudgetMs = 5;  // a budgeted frame keeps the resident levels: none of them either
    Renderer renderer(file, o);
    for (const Camera& c : cameraPath()) {
      FrameStats st;
      const ImageRGBA image = renderer.renderFrame(c, st);
      EXPECT_EQ(afam_test::largestAlpha(image), 0.f);
      EXPECT_EQ(st.bytesRead, 0u);
      EXPECT_EQ(st.slots, 0);
      EXPECT_EQ(st.culled.visibleBlocks, 0);
    }
  }
}

TEST(RankRenderers, RanksThatDisagreeOnTheirNumberAreRefused) {
  const auto file = headFile();
  try {
    rankBox(*file, 3, 3);
    FAIL() << "rank 3 of 3 accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("rank 3 of 3 ranks"), std::string::npos) << e.what();
  }
  EXPECT_THROW(rankBox(*file, -1, 2), InvalidArgument);
  EXPECT_THROW(rankBox(*file, 0, 0), InvalidArgument);
  // Images of 3 ranks composited in the order of a split among 2.
  ImageRGBA a;
  a.resize(4, 3);
  const float lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
  const std::vector<int> order = RankSplit::ofFile(*file, 2).visibilityOrder(
      cameraPath()[0].toRayCamera(), lo, hi, file->partition().dims());
  EXPECT_THROW(compositeRankImages({a, a, a}, order, kBlendComposite), InvalidArgument);
}
