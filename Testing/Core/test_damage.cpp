// SPDX-License-Identifier: BSD-3-Clause
// Damaged micro-models: skipped, replaced by the nearest intact level, reported once, not re-read.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "afam/base/errors.hpp"
#include "afam/render/level_decode.hpp"
#include "afam/render/raycast.hpp"
#include "afam/render/renderer.hpp"
#include "damaged_copy.hpp"
#include "render_test_util.hpp"

using namespace afam;

namespace {

using afam_test::damagedCopy;

RenderOptions options(int forceLevel) {
  RenderOptions o;
  o.threads = 2;
  o.sampleDistance = 0.01f;
  o.cache = CacheBudget{};
  o.lod.forceLevel = forceLevel;
  return o;
}

Camera camera(int size) {
  return Camera::lookAt({1.6, 1.9, 1.3}, {0, 0, 0}, {0, 0, 1}, 60, size, size);
}

bool rayHitsBox(const RayCamera& c, int x, int y, const double lo[3], const double hi[3],
                double margin) {
  float o[3], d[3], l[3], h[3], t0, t1;
  pixelRay(c, x, y, o, d);
  for (int a = 0; a < 3; ++a) {
    l[a] = float(lo[a] - margin);
    h[a] = float(hi[a] + margin);
  }
  return intersectBox(o, d, l, h, t0, t1);
}

int64_t foreground(const ImageRGBA& img) {
  int64_t n = 0;
  for (size_t i = 3; i < img.rgba.size(); i += 4) n += img.rgba[i] > 0.02f ? 1 : 0;
  return n;
}

struct Damaged {
  std::shared_ptr<const AfamFile> intact, damaged;
  int64_t e0, e1, e2a, e2b;  // level 0; level 1 (1,1,1); level 2 under an intact / a damaged parent
};

Damaged makeDamaged() {
  Damaged d;
  d.intact = afam_test::encodeMl(65, EncodingMode::Adaptive, 3, 4, 1e-3);
  const AfamFile& f = *d.intact;
  d.e0 = f.entryIndex(0, {0, 0, 0});
  d.e1 = f.entryIndex(1, {1, 1, 1});
  d.e2a = f.entryIndex(2, {1, 1, 0});  // parent (0, 0, 0) at level 1 is intact
  d.e2b = f.entryIndex(2, {2, 2, 2});  // parent (1, 1, 1) and level 0 damaged: left empty
  d.damaged = damagedCopy(f, afam_test::tempPath("damaged"), {d.e0, d.e1, d.e2a, d.e2b});
  return d;
}

}  // namespace

TEST(Damage, FinestCutDrawsAroundDamagedBlocksAndOnlyThere) {
  const Damaged d = makeDamaged();
  Renderer good(d.intact, options(2)), bad(d.damaged, options(2));
  const Camera c = camera(96);
  FrameStats sg, sb;
  const ImageRGBA ig = good.renderFrame(c, sg), ib = bad.renderFrame(c, sb);
  EXPECT_EQ(sb.damagedBlocks, 2);       // e2a and e2b are in the finest cut
  EXPECT_EQ(sb.emptyDamagedBlocks, 1);  // e2b: every ancestor damaged, no finer level
  EXPECT_EQ(sb.slots, sg.slots - 1);    // e2a drawn by its parent, e2b by nothing
  // e2a, then e2b with its two damaged ancestors: four blocks found, four reports.
  ASSERT_EQ(sb.damageReports.size(), 4u);
  EXPECT_EQ(sb.knownDamagedBlocks, 4);
  for (const std::string& r : sb.damageReports) {
    EXPECT_NE(r.find(d.damaged->path()), std::string::npos) << r;
    EXPECT_NE(r.find("checksum"), std::string::npos) << r;
    EXPECT_NE(r.find("afam verify"), std::string::npos) << r;
  }
  for (const char* block : {"level 2 block (1, 1, 0)", "level 2 block (2, 2, 2)",
                            "level 1 block (1, 1, 1)", "level 0 block (0, 0, 0)"}) {
    int n = 0;
    for (const std::string& r : sb.damageReports) n += r.find(block) != std::string::npos ? 1 : 0;
    EXPECT_EQ(n, 1) << block;
  }
  // Pixels whose rays miss both damaged blocks (widened by a voxel) are exactly the intact ones.
  const Partition& p = d.intact->partition();
  const RayCamera rc = c.toRayCamera();
  double lo[2][3], hi[2][3];
  blockBox(p, 2, {1, 1, 0}, lo[0], hi[0]);
  blockBox(p, 2, {2, 2, 2}, lo[1], hi[1]);
  int64_t outside = 0, differ = 0, inside = 0, changed = 0;
  for (int y = 0; y < c.height; ++y)
    for (int x = 0; x < c.width; ++x) {
      const size_t i = (size_t(y) * c.width + x) * 4;
      bool same = true;
      for (int k = 0; k < 4; ++k) same = same && ig.rgba[i + k] == ib.rgba[i + k];
      if (rayHitsBox(rc, x, y, lo[0], hi[0], 2.0 / 64) ||
          rayHitsBox(rc, x, y, lo[1], hi[1], 2.0 / 64)) {
        ++inside;
        changed += same ? 0 : 1;
      } else {
        ++outside;
        differ += same ? 0 : 1;
      }
    }
  std::printf("outside=%lld differ=%lld inside=%lld changed=%lld fg %lld / %lld\n",
              (long long)outside, (long long)differ, (long long)inside, (long long)changed,
              (long long)foreground(ib), (long long)foreground(ig));
  EXPECT_GT(outside, 4000);
  EXPECT_EQ(differ, 0);
  EXPECT_GT(changed, 50);  // the empty block shows
  EXPECT_GE(double(foreground(ib)), 0.8 * double(foreground(ig)));
  // Next frame: nothing re-read, nothing reported again, the same image.
  FrameStats s2;
  const ImageRGBA ib2 = bad.renderFrame(c, s2);
  EXPECT_EQ(s2.bytesRead, 0u);
  EXPECT_EQ(s2.damageReports.size(), 0u);
  EXPECT_EQ(s2.damagedBlocks, 2);
  EXPECT_EQ(s2.knownDamagedBlocks, 4);
  EXPECT_EQ(ib2.rgba, ib.rgba);
}

TEST(Damage, DamagedCoarseBlocksAreDrawnFromTheirIntactChildren) {
  const Damaged d = makeDamaged();
  const Camera c = camera(64);
  {
    // Level 0 damaged: its 8 children, of which (1,1,1) is damaged and drawn from its own 8
    // children less e2b: 7 + 7 models.
    Renderer good(d.intact, options(0)), bad(d.damaged, options(0));
    FrameStats sg, sb;
    const ImageRGBA ig = good.renderFrame(c, sg), ib = bad.renderFrame(c, sb);
    EXPECT_EQ(sg.slots, 1);
    EXPECT_EQ(sb.slots, 14);
    EXPECT_EQ(sb.damagedBlocks, 1);
    EXPECT_EQ(sb.emptyDamagedBlocks, 0);
    EXPECT_EQ(sb.damageReports.size(), 3u);  // e0, e1, e2b
    EXPECT_GE(double(foreground(ib)), 0.8 * double(foreground(ig)));
  }
  {
    // Level 1: e1's ancestor (level 0) is damaged, so e1 is drawn from its children less e2b.
    Renderer bad(d.damaged, options(1));
    FrameStats sb;
    bad.renderFrame(c, sb);
    EXPECT_EQ(sb.slots, 7 + 7);
    EXPECT_EQ(sb.damagedBlocks, 1);
    EXPECT_EQ(sb.damageReports.size(), 3u);
  }
}

TEST(Damage, PrefetchSkipsAndRecordsDamagedBlocks) {
  const Damaged d = makeDamaged();
  LruCache cache(d.damaged, CacheBudget{});
  EXPECT_FALSE(cache.prefetch(d.e1));  // damaged: read once, recorded, nothing cached
  EXPECT_EQ(cache.stats().blocksRead, 0u);
  EXPECT_TRUE(cache.isDamaged(d.e1));
  EXPECT_EQ(cache.damage().takeReports().size(), 1u);
  EXPECT_FALSE(cache.prefetch(d.e1));
  EXPECT_EQ(cache.getIntact(d.e1), nullptr);
  EXPECT_THROW(cache.get(d.e1), FormatError);
  EXPECT_EQ(cache.damage().takeReports().size(), 0u);
  EXPECT_TRUE(cache.prefetch(d.e0 + 1));  // an intact neighbour loads
  EXPECT_EQ(cache.stats().blocksRead, 1u);
}

// The bar of a user's damaged file: 8 bytes overwritten at 1.5%, 10%, 45% and 75% of the file's
// length (moved into the payload area when the spot falls in the header or index), screen-space
// LOD, six 300 x 300 views around the volume.
TEST(Damage, DamagedFileKeepsMostOfThePictureAndReportsEachBlockOnce) {
  auto intact = afam_test::encodeMl(65, EncodingMode::Adaptive, 3, 4, 1e-3);
  std::vector<int64_t> hit;
  for (double f : {0.015, 0.10, 0.45, 0.75}) {
    const uint64_t at =
        std::max<uint64_t>(uint64_t(f * double(intact->fileSize())), intact->payloadOffset());
    for (size_t i = 0; i < intact->entries().size(); ++i) {
      const ModelEntry& e = intact->entries()[i];
      if (at >= e.offset && at < e.offset + std::max<uint64_t>(e.storedSize, 1) &&
          e.storedSize >= 8) {
        hit.push_back(int64_t(i));
        break;
      }
    }
  }
  ASSERT_EQ(hit.size(), 4u);
  auto damaged = damagedCopy(*intact, afam_test::tempPath("damaged_bar"), hit);
  RenderOptions o = options(-1);
  o.lod.policy = LodPolicy::Screen;
  Renderer good(intact, o), bad(damaged, o);
  int64_t fgGood = 0, fgBad = 0;
  size_t messages = 0;
  for (int k = 0; k < 6; ++k) {
    const double a = k * 1.047;
    const Camera c = Camera::lookAt({2.6 * std::cos(a), 2.6 * std::sin(a), 1.0}, {0, 0, 0},
                                    {0, 0, 1}, 50, 300, 300);
    FrameStats sg, sb;
    fgGood += foreground(good.renderFrame(c, sg));
    fgBad += foreground(bad.renderFrame(c, sb));
    messages += sb.damageReports.size();
  }
  std::printf("levels hit %d %d %d %d; foreground %lld of %lld (%.1f%%), %zu messages\n",
              intact->entries()[size_t(hit[0])].level, intact->entries()[size_t(hit[1])].level,
              intact->entries()[size_t(hit[2])].level, intact->entries()[size_t(hit[3])].level,
              (long long)fgBad, (long long)fgGood, 100.0 * double(fgBad) / double(fgGood),
              messages);
  EXPECT_GE(double(fgBad), 0.8 * double(fgGood));
  EXPECT_GE(messages, 1u);
  EXPECT_LE(messages, 4u);
}

TEST(Damage, OneCoarseModelStandsInForSeveralDamagedSiblingsOnce) {
  auto intact = afam_test::encodeMl(65, EncodingMode::Adaptive, 3, 4, 1e-3);
  const int64_t a = intact->entryIndex(2, {0, 0, 0}), b = intact->entryIndex(2, {1, 0, 0});
  auto damaged = damagedCopy(*intact, afam_test::tempPath("damaged_siblings"), {a, b});
  auto log = std::make_shared<DamageLog>();
  PreparedFrame fr;
  {
    Renderer r(damaged, options(2), FrameSettings(options(2)), log);
    FrameStats st;
    r.prepare(camera(48), fr, st);
    EXPECT_EQ(st.damagedBlocks, 2);
    EXPECT_EQ(st.damageReports.size(), 2u);
  }
  // Both drawn by their parent (level 1, block (0, 0, 0)): one slot, not two.
  const int64_t parent = damaged->entryIndex(1, {0, 0, 0});
  EXPECT_EQ(std::count(fr.entries.begin(), fr.entries.end(), parent), 1);
  std::vector<int64_t> sorted = fr.entries;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end());
  EXPECT_EQ(fr.slots.size(), 64u - 2u + 1u);
  // A new renderer of the same file with the same log (the mapper after a change of cache budget):
  // nothing reported or read again.
  Renderer again(damaged, options(2), FrameSettings(options(2)), log);
  FrameStats st;
  again.renderFrame(camera(48), st);
  EXPECT_EQ(st.damageReports.size(), 0u);
  EXPECT_EQ(st.damagedBlocks, 2);
  EXPECT_EQ(again.cache().stats().blocksRead, 63u);
}

TEST(Damage, DecodedLevelTakesDamagedBlocksFromTheNearestIntactLevel) {
  const Damaged d = makeDamaged();
  const LevelGrid g2 = levelGrid(d.intact->partition(), 2),
                  g1 = levelGrid(d.intact->partition(), 1);
  const Index3 n = g2.dims, n1 = g1.dims;
  const auto all = [](const Index3& dims) { return Index3{dims[0] - 1, dims[1] - 1, dims[2] - 1}; };
  std::vector<float> intact(size_t(n[0] * n[1] * n[2])), damaged(intact.size()),
      coarse(size_t(n1[0] * n1[1] * n1[2]));
  decodeLevelBox(*d.intact, 2, {0, 0, 0}, all(n), intact.data());
  decodeLevelBox(*d.intact, 1, {0, 0, 0}, all(n1), coarse.data());
  // Strict callers (`afam decode`) still stop at the first damaged block.
  EXPECT_THROW(decodeLevelBox(*d.damaged, 2, {0, 0, 0}, all(n), damaged.data()), FormatError);
  std::vector<std::string> reports;
  decodeLevelBox(*d.damaged, 2, {0, 0, 0}, all(n), damaged.data(), {}, &reports);
  ASSERT_EQ(reports.size(), 2u);  // e2a and e2b, each named
  EXPECT_NE(reports[0].find("level 2 block (1, 1, 0)"), std::string::npos) << reports[0];
  EXPECT_NE(reports[1].find("level 2 block (2, 2, 2)"), std::string::npos) << reports[1];
  // 65^3 with 4 finest blocks: block i of level 2 owns samples [16 i, 16 i + 16) per axis.
  const auto owner = [](int64_t s) { return int(std::min<int64_t>(s / 16, 3)); };
  int64_t nan = 0, fromParent = 0, elsewhereDiffers = 0;
  double worstParent = 0;
  for (int64_t z = 0; z < n[2]; ++z)
    for (int64_t y = 0; y < n[1]; ++y)
      for (int64_t x = 0; x < n[0]; ++x) {
        const size_t i = size_t((z * n[1] + y) * n[0] + x);
        const Int3 b{owner(x), owner(y), owner(z)};
        if (b == Int3{2, 2, 2}) {  // every ancestor damaged, no finer level: no data
          nan += std::isnan(damaged[i]) ? 1 : 0;
        } else if (b == Int3{1, 1, 0}) {  // from its intact parent, level 1 block (0, 0, 0)
          if (x % 2 == 0 && y % 2 == 0 && z % 2 == 0) {  // where a level-1 sample sits
            const size_t c = size_t(((z / 2) * n1[1] + y / 2) * n1[0] + x / 2);
            worstParent = std::max(worstParent, double(std::fabs(damaged[i] - coarse[c])));
            ++fromParent;
          }
        } else {
          elsewhereDiffers += damaged[i] == intact[i] ? 0 : 1;
        }
      }
  EXPECT_EQ(nan, 16 * 16 * 16);
  EXPECT_EQ(fromParent, 8 * 8 * 8);
  EXPECT_LT(worstParent, 1e-4);  // the parent's own samples, up to evaluation order
  EXPECT_EQ(elsewhereDiffers, 0);
}
