// SPDX-License-Identifier: BSD-3-Clause
// The coarse levels filtered from a copy of the volume (level_sampler.hpp): the CPU reference gives
// sampleBlockRow's floats bit for bit (the GPU's are held to the same: Testing/Cuda), and an encode
// that loads it while it scans the range and asks it for the coarse levels writes the same models
// as one that reads and filters the volume for each level.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "afam/encode/encoder.hpp"
#include "afam/sampling/level_sampler.hpp"
#include "typed_volume.hpp"

using namespace afam;

using afam_test::loadAll;
using afam_test::TypedVolume;
using afam_test::typedVolume;

namespace {

struct GpuLikeFailure : Error {
  using Error::Error;
};

/// A sampler that counts what it is asked, the reference doing the work.
class CountingSampler : public LevelSampler {
 public:
  bool reserve(Index3 dims, SampleType type, std::string& why) override {
    ++reserves;
    if (refuse) {
      why = "refused by the test";
      return false;
    }
    reservedType = type;
    return cpu.reserve(dims, type, why);
  }
  void load(int64_t z0, int64_t nz, const void* samples) override {
    if (failLoad) throw GpuLikeFailure("a load failed");
    planes += nz;
    cpu.load(z0, nz, samples);
  }
  void sampleRow(const Partition& part, int level, const std::vector<Int3>& blocks, bool ghost,
                 LevelSampling sampling, std::vector<std::vector<float>*>& out,
                 const BlockLoop& loop) override {
    rows += 1;
    if (failRow == rows) throw GpuLikeFailure("a row failed");
    cpu.sampleRow(part, level, blocks, ghost, sampling, out, loop);
  }
  void release() override {
    ++releases;
    cpu.release();
  }
  std::string description() const override { return "counting"; }
  CpuLevelSampler cpu;
  bool refuse = false, failLoad = false;
  int64_t failRow = -1;
  SampleType reservedType = SampleType::Float64;
  int64_t planes = 0, rows = 0;
  int reserves = 0, releases = 0;
};

/// Three levels of three blocks per axis on `threads` threads (the default bound).
EncoderOptions threeLevels(int threads) {
  EncoderOptions opt;
  opt.levels = 3;
  opt.blocksPerAxis = 3;
  opt.threads = threads;
  return opt;
}

/// z-rows of blocks over the partition's levels coarser than the volume.
int64_t coarseRows(const Partition& part) {
  int64_t rows = 0;
  for (int l = 0; l + 1 < part.levels(); ++l) rows += part.blocksPerAxis(l)[2];
  return rows;
}

}  // namespace

TEST(LevelSampler, TheReferenceFiltersEveryCoarseRowAsTheSamplingBitForBit) {
  const Index3 dims{61, 50, 47};
  const Partition part(dims, 4, 4);
  for (const SampleType type : {SampleType::UInt8, SampleType::Int16, SampleType::Float32}) {
    const TypedVolume t = typedVolume(dims, type);
    CpuLevelSampler sampler;
    loadAll(sampler, t);
    const size_t compared = afam_test::compareRowsWithTheSampling(sampler, t, part);
    EXPECT_GT(compared, 4 * size_t(dims[0] * dims[1] * dims[2]));
  }
}

TEST(LevelSampler, AnEncodeLoadsItAsItScansAndAsksItForTheCoarseLevelsOnly) {
  const Index3 dims{61, 50, 47};
  for (const SampleType type : {SampleType::UInt8, SampleType::Float32}) {
    SCOPED_TRACE(sampleTypeName(type));
    const TypedVolume t = typedVolume(dims, type);
    EncoderOptions opt = threeLevels(3);
    opt.errorBound = 1e-2;
    opt.relativeBound = true;
    ArraySource plain(t.bytes.data(), type, dims);
    InMemoryModels without;
    const EncodeStats s0 = encodeVolume(plain, opt, without);
    EXPECT_EQ(s0.levelSampler, "");
    auto counting = std::make_shared<CountingSampler>();
    opt.levelSampler = counting;
    ArraySource src(t.bytes.data(), type, dims);
    InMemoryModels with;
    const EncodeStats s1 = encodeVolume(src, opt, with);
    EXPECT_EQ(s1.levelSampler, "counting");
    EXPECT_EQ(counting->reservedType, type);
    EXPECT_EQ(counting->planes, dims[2]);  // every plane once, as the range scan read it
    const Partition part(dims, opt.levels, opt.blocksPerAxis);
    EXPECT_EQ(counting->rows, coarseRows(part));
    EXPECT_EQ(counting->releases, 1);
    ASSERT_EQ(with.entries.size(), without.entries.size());
    EXPECT_EQ(with.stored, without.stored);
    EXPECT_GT(with.entries.size(), 20u);
  }
}

TEST(LevelSampler, MissingSamplesARefusalAndDSLeaveTheCoarseLevelsToTheCpu) {
  const Index3 dims{40, 36, 33};
  TypedVolume t = typedVolume(dims, SampleType::Float32);
  EncoderOptions opt = threeLevels(2);
  {  // a missing sample: the copy is dropped, the CPU filters (its rule for missing samples)
    std::vector<float> holed = t.floats;
    holed[1234] = std::nanf("");
    ArraySource plain(holed.data(), dims);
    InMemoryModels without, with;
    encodeVolume(plain, opt, without);
    auto counting = std::make_shared<CountingSampler>();
    opt.levelSampler = counting;
    ArraySource src(holed.data(), dims);
    const EncodeStats s = encodeVolume(src, opt, with);
    EXPECT_EQ(s.levelSampler, "not used: the volume has missing samples");
    EXPECT_EQ(counting->rows, 0);
    EXPECT_GE(counting->releases, 1);
    EXPECT_EQ(with.stored, without.stored);
  }
  {  // a sampler that cannot hold the volume
    auto counting = std::make_shared<CountingSampler>();
    counting->refuse = true;
    opt.levelSampler = counting;
    ArraySource src(t.floats.data(), dims);
    InMemoryModels models;
    const EncodeStats s = encodeVolume(src, opt, models);
    EXPECT_EQ(s.levelSampler, "not used: refused by the test");
    EXPECT_EQ(counting->planes, 0);
    EXPECT_EQ(counting->rows, 0);
  }
  {  // DS keeps the paper's strided samples: nothing to filter
    auto counting = std::make_shared<CountingSampler>();
    opt.levelSampler = counting;
    opt.mode = EncodingMode::Downsampled;
    ArraySource src(t.floats.data(), dims);
    InMemoryModels models;
    const EncodeStats s = encodeVolume(src, opt, models);
    EXPECT_EQ(s.levelSampler, "");
    EXPECT_EQ(counting->reserves, 0);
  }
}

TEST(LevelSampler, OneThatFailsLeavesTheCoarseLevelsToTheCpuSayingWhy) {
  const Index3 dims{61, 50, 47};
  const TypedVolume t = typedVolume(dims, SampleType::UInt8);
  EncoderOptions opt = threeLevels(3);
  ArraySource plain(t.bytes.data(), t.type, dims);
  InMemoryModels without;
  encodeVolume(plain, opt, without);
  // Encodes with `counting`: its report, and the models as the encode without it wrote them.
  const auto encodeWith = [&](const std::shared_ptr<CountingSampler>& counting) {
    opt.levelSampler = counting;
    ArraySource src(t.bytes.data(), t.type, dims);
    InMemoryModels models;
    const EncodeStats s = encodeVolume(src, opt, models);
    EXPECT_EQ(models.stored, without.stored);
    return s.levelSampler;
  };
  auto failedLoad = std::make_shared<CountingSampler>();  // the copy dropped after the scan
  failedLoad->failLoad = true;
  EXPECT_EQ(encodeWith(failedLoad), "not used: a load failed");
  EXPECT_EQ(failedLoad->rows, 0);
  auto failedRow = std::make_shared<CountingSampler>();  // the second: it and the rest on the CPU
  failedRow->failRow = 2;
  EXPECT_EQ(encodeWith(failedRow), "counting; failed, the rest filtered on the CPU: a row failed");
  EXPECT_EQ(failedRow->rows, 2);
}

namespace {
/// A source whose range is known (as a run's steps are, after the run's first pass).
class RangedArray : public ArraySource {
 public:
  using ArraySource::ArraySource;
  bool knownRange(double& lo, double& hi) const override {
    lo = 0;
    hi = 255;
    return true;
  }
};
}  // namespace

TEST(LevelSampler, AVolumeWhoseRangeIsKnownIsNotReadAgainToLoadIt) {
  const Index3 dims{40, 36, 33};
  const TypedVolume t = typedVolume(dims, SampleType::UInt8);
  EncoderOptions opt = threeLevels(2);
  auto counting = std::make_shared<CountingSampler>();
  opt.levelSampler = counting;
  RangedArray src(t.bytes.data(), t.type, dims);
  InMemoryModels models;
  const EncodeStats s = encodeVolume(src, opt, models);
  EXPECT_EQ(s.levelSampler, "not used: the range is known, and the volume is not scanned");
  EXPECT_EQ(counting->reserves, 0);
  EXPECT_EQ(counting->planes, 0);
  EXPECT_EQ(s.valueMax, 255);
}
