// SPDX-License-Identifier: BSD-3-Clause
// The split of a volume among ranks (rank_boxes.hpp): boxes that tile the finest block grid, work
// balanced on a skewed file, the same split every time, any number of ranks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <random>

#include "afam/base/errors.hpp"
#include "afam/ranks/rank_boxes.hpp"
#include "skewed_blob.hpp"

using namespace afam;

namespace {

/// A 7 x 5 x 3 grid whose work grows steeply towards one corner (a few blocks hold most of it).
CellGrid skewedGrid() {
  CellGrid g;
  g.cells = {7, 5, 3};
  g.levels = 2;
  for (int a = 0; a < 3; ++a)
    for (int i = 0; i <= g.cells[a]; ++i) g.bounds[size_t(a)].push_back(int64_t(i) * (10 + a));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(0.5, 1.5);
  for (int z = 0; z < 3; ++z)
    for (int y = 0; y < 5; ++y)
      for (int x = 0; x < 7; ++x) g.work.push_back(std::pow(3.0, x + y) * jitter(rng));
  return g;
}

/// How many boxes of `split` hold each cell of `g`.
std::vector<int> coverage(const CellGrid& g, const RankSplit& split) {
  std::vector<int> count(g.work.size(), 0);
  for (const CellBox& b : split.boxes())
    for (int z = b.lo[2]; z < b.hi[2]; ++z)
      for (int y = b.lo[1]; y < b.hi[1]; ++y)
        for (int x = b.lo[0]; x < b.hi[0]; ++x)
          ++count[(size_t(z) * g.cells[1] + size_t(y)) * g.cells[0] + size_t(x)];
  return count;
}

double maxOverMean(const std::vector<double>& values) {
  double sum = 0, most = 0;
  for (double v : values) sum += v, most = std::max(most, v);
  return most / (sum / double(values.size()));
}

}  // namespace

TEST(RankBoxes, TileTheGridExactlyForAnyCountOfRanks) {
  const CellGrid g = skewedGrid();
  const int64_t cells = int64_t(g.work.size());
  for (int ranks : {1, 2, 3, 4, 5, 7, 8, 16, 33, 104, 105, 106, 200}) {
    SCOPED_TRACE(ranks);
    const RankSplit split(g, ranks);
    ASSERT_EQ(split.boxes().size(), size_t(ranks));
    for (int c : coverage(g, split)) EXPECT_EQ(c, 1);  // every cell in exactly one box
    int64_t nonEmpty = 0;
    for (const CellBox& b : split.boxes()) {
      if (b.empty()) continue;
      ++nonEmpty;
      for (int a = 0; a < 3; ++a) {
        EXPECT_GE(b.lo[a], 0);
        EXPECT_LE(b.hi[a], g.cells[a]);
      }
      if (ranks >= cells) {
        EXPECT_EQ(b.cells(), 1);
      }
    }
    EXPECT_EQ(nonEmpty, std::min<int64_t>(ranks, cells));
  }
  const RankSplit one(g, 1);
  EXPECT_EQ(one.boxes()[0], (CellBox{{0, 0, 0}, {7, 5, 3}}));
}

TEST(RankBoxes, BalanceTheWorkOfASkewedFileNotItsVolume) {
  const auto file = afam_test::encodeSkewedBlob();
  const CellGrid g = cellWork(*file);
  ASSERT_EQ(g.cells, (Int3{8, 8, 8}));
  const Partition& p = file->partition();
  for (int ranks : {2, 3, 4, 8}) {
    const RankSplit split = RankSplit::ofFile(*file, ranks);
    std::vector<double> voxels;
    for (const CellBox& b : split.boxes()) {
      double v = 1;
      for (int a = 0; a < 3; ++a) {
        // A box's faces are finest block boundaries of the file's partition.
        const BlockExtent lo = p.extent(p.levels() - 1, b.lo);
        EXPECT_EQ(g.bounds[size_t(a)][size_t(b.lo[a])], lo.lo[size_t(a)]);
        v *= double(g.bounds[size_t(a)][size_t(b.hi[a])] - g.bounds[size_t(a)][size_t(b.lo[a])]);
      }
      voxels.push_back(v);
    }
    const double workFactor = maxOverMean(split.work());
    const double volumeFactor = maxOverMean(voxels);
    std::printf(
        "rank boxes of the skewed blob, %d ranks: work max/mean %.3f, volume max/mean %.3f\n",
        ranks, workFactor, volumeFactor);
    EXPECT_LE(workFactor, 1.25) << ranks << " ranks";
    EXPECT_GE(volumeFactor, 1.5) << ranks << " ranks: balanced by volume, not by work";
  }
}

TEST(RankBoxes, TheSameSplitFromTheFileEveryTime) {
  const auto a = afam_test::encodeSkewedBlob();
  const auto b = AfamFile::open(a->path());  // another rank's handle
  for (int ranks : {3, 5, 64}) {
    const RankSplit x = RankSplit::ofFile(*a, ranks), y = RankSplit::ofFile(*b, ranks);
    EXPECT_EQ(x.boxes(), y.boxes());
    EXPECT_EQ(x.work(), y.work());
  }
}

TEST(RankBoxes, HugeCountsGiveEmptyBoxesAndBadCountsAreRefused) {
  const CellGrid g = skewedGrid();
  const RankSplit huge(g, kMaxRanks);
  int64_t empty = 0;
  for (const CellBox& b : huge.boxes()) empty += b.empty() ? 1 : 0;
  EXPECT_EQ(empty, kMaxRanks - 105);
  for (int bad : {0, -3, kMaxRanks + 1}) {
    try {
      RankSplit split(g, bad);
      ADD_FAILURE() << bad << " ranks accepted";
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find(std::to_string(bad) + " ranks"), std::string::npos);
    }
  }
  CellGrid wrong = g;
  wrong.work.pop_back();
  EXPECT_THROW(RankSplit(wrong, 2), InvalidArgument);
  wrong = g;
  wrong.work[3] = -1;
  EXPECT_THROW(RankSplit(wrong, 2), InvalidArgument);
}

TEST(RankBoxes, VisibilityOrderStartsNearTheEyeAndEmptyBoxesComeLast) {
  const CellGrid g = skewedGrid();
  const RankSplit split(g, 9);
  const float lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
  const Index3 dims{71, 56, 37};  // the grid's last boundaries, plus one
  RayCamera cam;
  const float eyes[2][3] = {{-3, -2, -4}, {3, 2, 4}};
  for (int e = 0; e < 2; ++e) {
    for (int a = 0; a < 3; ++a) cam.eye[a] = eyes[e][a];
    const std::vector<int> order = split.visibilityOrder(cam, lo, hi, dims);
    ASSERT_EQ(order.size(), 9u);
    const Int3 nearest = e == 0 ? Int3{0, 0, 0} : Int3{6, 4, 2};
    const Int3 farthest = e == 0 ? Int3{6, 4, 2} : Int3{0, 0, 0};
    EXPECT_TRUE(split.boxes()[size_t(order.front())].contains(nearest));
    EXPECT_TRUE(split.boxes()[size_t(order.back())].contains(farthest));
  }
  const RankSplit many(g, 110);
  const std::vector<int> order = many.visibilityOrder(cam, lo, hi, dims);
  ASSERT_EQ(order.size(), 110u);
  for (size_t i = 105; i < 110; ++i) EXPECT_TRUE(many.boxes()[size_t(order[i])].empty());
}
