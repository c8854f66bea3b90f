// SPDX-License-Identifier: BSD-3-Clause
// Block sampling from a streaming source: with ChunkBudget::QuarterOfSamples a row of blocks is
// read in chunks of planes bounded by the samples it fills (what an encoding rank holds beside its
// piece), and the chunking does not change a sample (each block alone is sampled in other chunks).
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "afam/encode/block_sampling.hpp"
#include "afam/volume/marschner_lobb.hpp"

using namespace afam;

namespace {

/// A source that records the largest read (in floats) and the number of reads.
class CountingSource : public ArraySource {
 public:
  using ArraySource::ArraySource;
  void readRows(int64_t z0, int64_t nz, int64_t y0, int64_t ny, float* out) override {
    largest = std::max(largest, size_t(nz * ny * dims()[0]));
    ++reads;
    ArraySource::readRows(z0, nz, y0, ny, out);
  }
  size_t largest = 0;
  int reads = 0;
};

struct RowCase {
  LevelSampling sampling;
  bool ghost;
};

}  // namespace

TEST(BlockSampling, QuarterBudgetChunksHoldAQuarterOfTheRowOrOneSamplesPlanes) {
  const Index3 dims{96, 80, 88};
  std::vector<float> v(size_t(dims[0] * dims[1] * dims[2]));
  marschnerLobbSlab(MarschnerLobb{}, dims, 0, dims[2], v.data());
  const Partition part(dims, 4, 8);
  for (const RowCase rc : {RowCase{LevelSampling::Point, false}, RowCase{LevelSampling::Box, false},
                           RowCase{LevelSampling::Box, true}}) {
    for (int l = 0; l < part.levels(); ++l) {
      const Int3 nb = part.blocksPerAxis(l);
      for (int kz = 0; kz < nb[2]; ++kz) {
        SCOPED_TRACE(testing::Message()
                     << "level " << l << " z-row " << kz << " box "
                     << (rc.sampling == LevelSampling::Box) << " ghost " << rc.ghost);
        CountingSource src(v.data(), dims);
        PlaneReader planes(src, dims);
        std::vector<Int3> row;
        for (int j = 0; j < nb[1]; ++j)
          for (int i = 0; i < nb[0]; ++i) row.push_back({i, j, kz});
        std::vector<std::vector<float>> samples(row.size());
        std::vector<std::vector<float>*> outs;
        size_t rowFloats = 0;
        for (auto& s : samples) outs.push_back(&s);
        sampleBlockRow(part, planes, l, row, rc.ghost, rc.sampling, outs, {},
                       ChunkBudget::QuarterOfSamples);
        for (const auto& s : samples) rowFloats += s.size();
        // One z-sample's planes: a box of width stride + the ghost's step, whole rows of the
        // volume.
        const size_t oneSample = size_t(part.stride(l) + 2) * size_t(dims[0] * dims[1]);
        EXPECT_LE(src.largest, std::max(rowFloats / 4, oneSample));
        EXPECT_EQ(planes.bufferBytes() % (sizeof(float) * size_t(dims[0])), 0u);
        EXPECT_LE(planes.bufferBytes(), sizeof(float) * std::max(rowFloats / 4, oneSample));
        // The same samples as each block sampled alone (other chunks) from the whole volume.
        for (size_t b = 0; b < row.size(); ++b) {
          ASSERT_EQ(samples[b], extractBlock(part, v.data(), l, row[b], rc.ghost, rc.sampling))
              << "block " << b;
        }
        if (l == part.levels() - 1 && !rc.ghost) {
          EXPECT_GT(src.reads, 1) << "a finest row is read in several chunks";
        }
      }
    }
  }
}
