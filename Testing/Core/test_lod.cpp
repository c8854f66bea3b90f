// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <random>

#include "afam/scene/camera.hpp"
#include "afam/scene/lod.hpp"

using namespace afam;

namespace {

/// Counts how many cut blocks cover each finest cell.
std::vector<int> coverage(const Partition& p, const std::vector<BlockRef>& cut) {
  const int finest = p.levels() - 1;
  const Int3 bf = p.blocksPerAxis(finest);
  std::vector<int> count(static_cast<size_t>(bf[0]) * bf[1] * bf[2], 0);
  for (const BlockRef& b : cut) {
    const int r = p.stride(b.level);
    for (int z = b.ijk[2] * r; z < std::min((b.ijk[2] + 1) * r, bf[2]); ++z)
      for (int y = b.ijk[1] * r; y < std::min((b.ijk[1] + 1) * r, bf[1]); ++y)
        for (int x = b.ijk[0] * r; x < std::min((b.ijk[0] + 1) * r, bf[0]); ++x)
          count[(size_t(z) * bf[1] + y) * bf[0] + x]++;
  }
  return count;
}

}  // namespace

TEST(Lod, CutCoversTheDomainExactlyOnceForManyViews) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> dist(0.3, 4.0), theta(0, 180), phi(-180, 180);
  for (const Index3 dims : {Index3{65, 65, 65}, Index3{50, 33, 71}, Index3{9, 200, 17}}) {
    const Partition p(dims, 4, 16);
    for (LodPolicy policy : {LodPolicy::Distance, LodPolicy::Screen}) {
      LodOptions o;
      o.policy = policy;
      const LodSelector sel(o);
      for (int i = 0; i < 60; ++i) {
        const Camera c = Camera::fromPose({dist(rng), theta(rng), phi(rng)}, 64, 64);
        const auto cut = sel.cut(p, c);
        for (int n : coverage(p, cut)) ASSERT_EQ(n, 1);
      }
    }
  }
}

TEST(Lod, DistanceBandsPickThePapersLevels) {
  const Partition p({129, 129, 129}, 4, 16);
  const LodSelector sel;
  // Camera at a corner, far: every block beyond 2.4 -> coarsest level.
  Camera far = Camera::fromPose({20.0, 45, 45}, 64, 64);
  for (const BlockRef& b : sel.cut(p, far)) EXPECT_EQ(b.level, 0);
  // Camera at the centre: the blocks around it are finest, and every block's level follows the
  // band of its centroid distance (or is the finest level of a refined parent).
  Camera centre = Camera::fromPose({1e-3, 10, 10}, 64, 64);
  const auto cut = sel.cut(p, centre);
  int finest = 0;
  for (const BlockRef& b : cut) {
    double lo[3], hi[3];
    blockBox(p, b.level, b.ijk, lo, hi);
    double d2 = 0;
    for (int a = 0; a < 3; ++a) d2 += std::pow(0.5 * (lo[a] + hi[a]) - centre.eye[a], 2);
    const int band = int(std::sqrt(d2) / 0.8);
    EXPECT_GE(b.level, std::max(0, 3 - band));
    finest += b.level == 3;
  }
  EXPECT_GT(finest, 0);
}

TEST(Lod, FrustumCullingKeepsEveryBlockARayCanReach) {
  const Partition p({65, 65, 65}, 3, 8);
  const LodSelector sel;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> dist(0.5, 3.0), theta(0, 180), phi(-180, 180), uv(-1, 1),
      t(0, 6);
  int culled = 0;
  for (int i = 0; i < 20; ++i) {
    const Camera c = Camera::fromPose({dist(rng), theta(rng), phi(rng)}, 32, 32);
    const auto cut = sel.cut(p, c);
    for (const BlockRef& b : cut) {
      double lo[3], hi[3];
      blockBox(p, b.level, b.ijk, lo, hi);
      culled += LodSelector::outsideFrustum(c, lo, hi);
    }
    // Points along random rays inside the volume must lie in non-culled blocks.
    for (int k = 0; k < 300; ++k) {
      const double su = uv(rng) * c.tanHalfX, sv = uv(rng) * c.tanHalfY,
                   tt = c.nearDistance + t(rng);
      double q[3];
      for (int a = 0; a < 3; ++a)
        q[a] = c.eye[a] + tt * (c.forward[a] + su * c.right[a] + sv * c.up[a]);
      if (std::abs(q[0]) > 1 || std::abs(q[1]) > 1 || std::abs(q[2]) > 1) continue;
      for (const BlockRef& b : cut) {
        double lo[3], hi[3];
        blockBox(p, b.level, b.ijk, lo, hi);
        const bool inside = q[0] >= lo[0] && q[0] <= hi[0] && q[1] >= lo[1] && q[1] <= hi[1] &&
                            q[2] >= lo[2] && q[2] <= hi[2];
        if (inside) {
          ASSERT_FALSE(LodSelector::outsideFrustum(c, lo, hi));
        }
      }
    }
  }
  EXPECT_GT(culled, 0);  // a 14-degree view from inside or near the volume misses blocks
}

TEST(Lod, ScreenPolicyRefinesNearAndCoarsensFar) {
  const Partition p({257, 257, 257}, 4, 16);
  LodOptions o;
  o.policy = LodPolicy::Screen;
  const LodSelector sel(o);
  const auto nearCut = sel.cut(p, Camera::fromPose({1.2, 30, 30}, 512, 512));
  const auto farCut = sel.cut(p, Camera::fromPose({40.0, 30, 30}, 64, 64));
  EXPECT_GT(nearCut.size(), farCut.size());
  for (const BlockRef& b : farCut) EXPECT_EQ(b.level, 0);
}
