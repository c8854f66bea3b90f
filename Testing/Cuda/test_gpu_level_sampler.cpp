// SPDX-License-Identifier: BSD-3-Clause
// The coarse levels filtered on the GPU (make_gpu_level_sampler.hpp) against the sampling on the
// CPU: the same floats bit for bit for every type it holds, every level, box and point taps, with
// and without ghosts; an encode that loads it writes the CPU encoder's file; a budget below the
// volume refuses it with the reason, and the encode is the same.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "../Core/typed_volume.hpp"
#include "afam/cuda/common/gpu_error.hpp"
#include "afam/cuda/encode/make_gpu_level_sampler.hpp"
#include "afam/encode/encoder.hpp"

namespace afam {
namespace {

std::shared_ptr<LevelSampler> gpuSampler(size_t budget = 0) {
  return makeGpuLevelSampler([](const std::string& why) { std::printf("gpu: %s\n", why.c_str()); },
                             -1, budget);
}

TEST(GpuLevelSampler, RowsEqualTheSamplingBitForBit) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  const Index3 dims{61, 50, 47};
  const Partition part(dims, 4, 4);
  for (const SampleType type :
       {SampleType::UInt8, SampleType::Int16, SampleType::Float32, SampleType::UInt16}) {
    auto gpu = gpuSampler();
    ASSERT_TRUE(gpu);
    afam_test::TypedVolume t =
        afam_test::typedVolume(dims, type == SampleType::UInt16 ? SampleType::Int16 : type);
    t.type = type;  // the int16 bytes read as uint16: large values, the same comparison
    afam_test::loadAll(*gpu, t);
    EXPECT_GT(afam_test::compareRowsWithTheSampling(*gpu, t, part),
              4 * size_t(dims[0] * dims[1] * dims[2]));
  }
}

TEST(GpuLevelSampler, AnEncodeWritesTheCpuEncodersModelsAndABudgetRefusesWithItsReason) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  const Index3 dims{97, 88, 75};
  const afam_test::TypedVolume t = afam_test::typedVolume(dims, SampleType::UInt8);
  EncoderOptions opt;
  opt.levels = 3;
  opt.blocksPerAxis = 3;
  opt.errorBound = 1e-2;
  opt.relativeBound = true;
  ArraySource cpuSource(t.bytes.data(), t.type, dims);
  InMemoryModels cpu;
  encodeVolume(cpuSource, opt, cpu);
  opt.levelSampler = gpuSampler();
  ASSERT_TRUE(opt.levelSampler);
  for (int run = 0; run < 2; ++run) {  // the copy of the encode before is reused
    ArraySource src(t.bytes.data(), t.type, dims);
    InMemoryModels gpu;
    const EncodeStats s = encodeVolume(src, opt, gpu);
    EXPECT_EQ(s.levelSampler, opt.levelSampler->description());
    EXPECT_EQ(gpu.stored, cpu.stored);
  }
  opt.levelSampler = gpuSampler(size_t(dims[0] * dims[1] * dims[2]) - 1);
  ArraySource src(t.bytes.data(), t.type, dims);
  InMemoryModels refused;
  const EncodeStats s = encodeVolume(src, opt, refused);
  EXPECT_NE(s.levelSampler.find("not used: the volume's copy"), std::string::npos)
      << s.levelSampler;
  EXPECT_NE(s.levelSampler.find("over its budget"), std::string::npos) << s.levelSampler;
  EXPECT_EQ(refused.stored, cpu.stored);
}

}  // namespace
}  // namespace afam
