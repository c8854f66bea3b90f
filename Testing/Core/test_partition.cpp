// SPDX-License-Identifier: BSD-3-Clause
// Partition: coverage, shared boundaries, parents/children, and the paper's level sizes.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "afam/base/errors.hpp"
#include "afam/format/partition.hpp"

using afam::BlockExtent;
using afam::CellBox;
using afam::Index3;
using afam::Int3;
using afam::InvalidArgument;
using afam::Partition;

namespace {

// Every level: along each axis the blocks tile [0, N-1] with shared boundary samples, the first
// starts at 0 and the last ends at N-1; sample positions are within the block and increasing.
void checkPartition(Index3 dims, int levels, int blocks) {
  SCOPED_TRACE(testing::Message() << dims[0] << "x" << dims[1] << "x" << dims[2] << " L=" << levels
                                  << " B=" << blocks);
  const Partition p(dims, levels, blocks);
  int64_t total = 0;
  for (int l = 0; l < levels; ++l) {
    const Int3 nb = p.blocksPerAxis(l);
    total += p.blockCount(l);
    EXPECT_EQ(p.blockCount(l), int64_t(nb[0]) * nb[1] * nb[2]);
    for (int a = 0; a < 3; ++a) {
      ASSERT_GE(nb[a], 1);
      Int3 ijk{0, 0, 0};
      int64_t prevHi = 0;
      for (int i = 0; i < nb[a]; ++i) {
        ijk[a] = i;
        const auto e = p.extent(l, ijk);
        EXPECT_EQ(e.lo[a], prevHi) << "blocks share their boundary sample";
        EXPECT_GE(e.hi[a], e.lo[a]);
        if (dims[a] > 1) {
          EXPECT_GT(e.hi[a], e.lo[a]);
        }
        prevHi = e.hi[a];
        ASSERT_GE(e.samples[a], 1);
        if (e.hi[a] > e.lo[a]) {
          EXPECT_GE(e.samples[a], 2);
          // Stride r: n about extent / r + 1.
          const double r = p.stride(l);
          EXPECT_EQ(e.samples[a],
                    std::max<int64_t>(2, std::llround(double(e.hi[a] - e.lo[a]) / r) + 1));
        }
        EXPECT_DOUBLE_EQ(p.samplePosition(e, a, 0), double(e.lo[a]));
        EXPECT_DOUBLE_EQ(p.samplePosition(e, a, e.samples[a] - 1), double(e.hi[a]));
        for (int k = 1; k < e.samples[a]; ++k)
          EXPECT_GT(p.samplePosition(e, a, k), p.samplePosition(e, a, k - 1));
      }
      EXPECT_EQ(prevHi, dims[a] - 1) << "the last block ends at the last sample";
    }
    // Linear index round trip and parent/children consistency.
    for (int64_t li = 0; li < p.blockCount(l); ++li) {
      const Int3 ijk = p.blockFromLinear(l, li);
      ASSERT_EQ(p.linearIndex(l, ijk), li);
      if (l + 1 < levels) {
        const auto ch = p.children(l, ijk);
        EXPECT_GE(ch.size(), 1u);
        EXPECT_LE(ch.size(), 8u);
        for (const Int3& c : ch) {
          EXPECT_EQ(p.parent(l + 1, c), ijk);
          // A child lies inside its parent.
          const auto pe = p.extent(l, ijk), ce = p.extent(l + 1, c);
          for (int a = 0; a < 3; ++a) {
            EXPECT_GE(ce.lo[a], pe.lo[a]);
            EXPECT_LE(ce.hi[a], pe.hi[a]);
          }
        }
      }
    }
  }
  EXPECT_EQ(p.totalBlockCount(), total);
  // Every finer block has exactly one parent, and the children of all parents cover the level.
  for (int l = 1; l < levels; ++l) {
    std::set<int64_t> seen;
    for (int64_t li = 0; li < p.blockCount(l - 1); ++li)
      for (const Int3& c : p.children(l - 1, p.blockFromLinear(l - 1, li)))
        EXPECT_TRUE(seen.insert(p.linearIndex(l, c)).second);
    EXPECT_EQ(int64_t(seen.size()), p.blockCount(l));
  }
}

}  // namespace

TEST(Partition, PaperLayout1201) {
  const Partition p({1201, 1201, 1201}, 4, 16);
  for (int l = 0; l < 4; ++l) {
    const Int3 nb = p.blocksPerAxis(l);
    EXPECT_EQ(nb[0], 2 << l);
    const auto e = p.extent(l, {0, 0, 0});
    EXPECT_EQ(e.samples[0], 76) << "the authors' 76 samples per axis for 1201^3";
  }
  EXPECT_EQ(p.totalBlockCount(), 8 + 64 + 512 + 4096);
  checkPartition({1201, 1201, 1201}, 4, 16);
}

TEST(Partition, Ml512) {
  const Partition p({512, 512, 512}, 4, 16);
  const auto e = p.extent(3, {0, 0, 0});
  EXPECT_GE(e.samples[0], 32);
  EXPECT_LE(e.samples[0], 34);
  checkPartition({512, 512, 512}, 4, 16);
  checkPartition({513, 513, 513}, 4, 16);
}

TEST(Partition, LevelSizes) {
  checkPartition({1024, 1024, 1024}, 4, 16);
  checkPartition({1024, 1024, 1088}, 4, 16);
  checkPartition({50, 50, 50}, 4, 16);
  checkPartition({64, 64, 93}, 4, 16);
  checkPartition({48, 62, 42}, 4, 16);
  checkPartition({66, 66, 66}, 3, 8);
}

TEST(Partition, Slabs) {
  checkPartition({64, 64, 1}, 4, 16);
  checkPartition({1, 64, 64}, 4, 16);
  checkPartition({1, 1, 200}, 4, 16);
  checkPartition({1, 1, 1}, 4, 16);
  checkPartition({2, 2, 2}, 4, 16);
  checkPartition({3, 5, 7}, 4, 16);
  const Partition p({64, 64, 1}, 4, 16);
  const auto e = p.extent(3, {0, 0, 0});
  EXPECT_EQ(e.samples[2], 1);
  EXPECT_EQ(p.blocksPerAxis(3)[2], 1);
}

TEST(Partition, ManyLevelsAndBlocks) {
  checkPartition({100, 100, 100}, 6, 5);
  checkPartition({33, 17, 9}, 5, 32);
  checkPartition({257, 257, 257}, 1, 1);
}

TEST(Partition, InvalidArguments) {
  EXPECT_THROW(Partition({0, 1, 1}, 4, 16), afam::InvalidArgument);
  EXPECT_THROW(Partition({8, 8, 8}, 0, 16), afam::InvalidArgument);
  EXPECT_THROW(Partition({8, 8, 8}, 17, 16), afam::InvalidArgument);
  EXPECT_THROW(Partition({8, 8, 8}, 4, 0), afam::InvalidArgument);
  const Partition p({8, 8, 8}, 2, 4);
  EXPECT_THROW(p.extent(0, {2, 0, 0}), afam::InvalidArgument);
  EXPECT_THROW(p.extent(1, {0, -1, 0}), afam::InvalidArgument);
}

TEST(Partition, BlockName) {
  EXPECT_EQ(Partition::blockName(2, {3, 0, 7}), "level 2 block (3, 0, 7)");
  EXPECT_EQ(Partition::blockName(0, {0, 0, 0}), "level 0 block (0, 0, 0)");
}

TEST(Partition, DefaultShapeFollowsTheDimensions) {
  auto shape = [](afam::Index3 d) {
    const afam::PartitionShape s = afam::defaultPartition(d);
    return std::array<int, 2>{s.levels, s.blocksPerAxis};
  };
  EXPECT_EQ(shape({1025, 1025, 1025}), (std::array<int, 2>{4, 16}))
      << "the paper's setting at 1024^3";
  EXPECT_EQ(shape({1024, 1024, 1024}), (std::array<int, 2>{4, 16}));
  EXPECT_EQ(shape({257, 257, 257}), (std::array<int, 2>{2, 4}));
  EXPECT_EQ(shape({66, 66, 66}), (std::array<int, 2>{1, 1}));
  EXPECT_EQ(shape({2049, 100, 3}), (std::array<int, 2>{5, 32})) << "the longest axis decides";
  EXPECT_EQ(shape({1, 1, 1}), (std::array<int, 2>{1, 1}));
  EXPECT_THROW(afam::defaultPartition({64, 64, 64}, 1), afam::InvalidArgument);
}

TEST(Partition, SamplesOfABoxOfFinestBlocks) {
  // 101 samples in 4 finest blocks along x (boundaries 0, 25, 50, 75, 100), 9 in 1 along y, z.
  const Partition p({101, 9, 9}, 2, 4);
  ASSERT_EQ(p.blocksPerAxis(1)[0], 4);
  const BlockExtent whole = p.samples(CellBox{{0, 0, 0}, p.blocksPerAxis(1)});
  EXPECT_EQ(whole.lo, (Index3{0, 0, 0}));
  EXPECT_EQ(whole.hi, (Index3{100, 8, 8}));
  // Two boxes that meet share the boundary sample, as the blocks they hold do.
  const BlockExtent low = p.samples(CellBox{{0, 0, 0}, {1, 1, 1}});
  const BlockExtent high = p.samples(CellBox{{1, 0, 0}, {4, 1, 1}});
  EXPECT_EQ(low.hi[0], p.extent(1, {0, 0, 0}).hi[0]);
  EXPECT_EQ(high.lo[0], low.hi[0]);
  EXPECT_EQ(high.hi[0], 100);
  EXPECT_EQ(high.samples[0], 100 - low.hi[0] + 1);
  const BlockExtent none = p.samples(CellBox{});
  EXPECT_EQ(none.lo, (Index3{0, 0, 0}));
  EXPECT_EQ(none.hi, (Index3{0, 0, 0}));
  EXPECT_THROW(p.samples(CellBox{{0, 0, 0}, {5, 1, 1}}), InvalidArgument);
  EXPECT_THROW(p.samples(CellBox{{-1, 0, 0}, {1, 1, 1}}), InvalidArgument);
}
