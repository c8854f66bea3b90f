// SPDX-License-Identifier: BSD-3-Clause
// EnlargedScanSource: a small volume resampled to any size with noise at the new resolution.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/volume/enlarged_scan.hpp"
#include "afam/volume/sample_type.hpp"

using namespace afam;

namespace {

std::vector<float> readAll(EnlargedScanSource& s) {
  const Index3 d = s.dims();
  std::vector<float> out(size_t(d[0] * d[1] * d[2]));
  s.readSlab(0, d[2], out.data());
  return out;
}

}  // namespace

TEST(EnlargedScan, ReproducesALinearFieldWithoutNoise) {
  const Index3 dims{5, 4, 6};
  std::vector<float> ramp;
  for (int z = 0; z < dims[2]; ++z)
    for (int y = 0; y < dims[1]; ++y)
      for (int x = 0; x < dims[0]; ++x) ramp.push_back(float(2 * x - 3 * y + 0.5 * z + 10));
  const Index3 big{17, 10, 21};
  EnlargedScanSource s(ramp, dims, big, 0.0, 1, -1e9, 1e9);
  const std::vector<float> v = readAll(s);
  double worst = 0;
  for (int64_t z = 0; z < big[2]; ++z)
    for (int64_t y = 0; y < big[1]; ++y)
      for (int64_t x = 0; x < big[0]; ++x) {
        const double sx = double(x) * (dims[0] - 1) / (big[0] - 1),
                     sy = double(y) * (dims[1] - 1) / (big[1] - 1),
                     sz = double(z) * (dims[2] - 1) / (big[2] - 1);
        const double want = 2 * sx - 3 * sy + 0.5 * sz + 10;
        worst = std::max(worst, std::fabs(v[size_t((z * big[1] + y) * big[0] + x)] - want));
      }
  EXPECT_LT(worst, 1e-4) << "Catmull-Rom reproduces linear functions";
}

TEST(EnlargedScan, SlabsAreTheSameHoweverTheVolumeIsCut) {
  std::mt19937 rng(3);
  std::vector<float> src(6 * 5 * 4);
  for (float& f : src) f = float(rng() % 200);
  const Index3 big{13, 11, 9};
  EnlargedScanSource whole(src, {6, 5, 4}, big, 4.0, 42, 0, 255);
  const std::vector<float> all = readAll(whole);
  EnlargedScanSource cut(src, {6, 5, 4}, big, 4.0, 42, 0, 255);
  std::vector<float> plane(size_t(big[0] * big[1]));
  for (int64_t z = 0; z < big[2]; ++z) {
    cut.readSlab(z, 1, plane.data());
    for (size_t i = 0; i < plane.size(); ++i)
      ASSERT_EQ(plane[i], all[size_t(z) * plane.size() + i]) << z;
  }
  EnlargedScanSource otherSeed(src, {6, 5, 4}, big, 4.0, 43, 0, 255);
  EXPECT_NE(readAll(otherSeed), all) << "the seed changes the noise";
}

TEST(EnlargedScan, NoiseHasTheAskedDeviationAndStaysInRange) {
  const std::vector<float> flat(4 * 4 * 4, 100.f);
  EnlargedScanSource s(flat, {4, 4, 4}, {64, 64, 32}, 5.0, 7, 0, 255);
  const std::vector<float> v = readAll(s);
  double sum = 0, sq = 0;
  for (float f : v) {
    sum += f;
    sq += double(f) * f;
  }
  const double mean = sum / double(v.size()), sd = std::sqrt(sq / double(v.size()) - mean * mean);
  EXPECT_NEAR(mean, 100.0, 0.1);
  EXPECT_NEAR(sd, 5.0, 0.1);
  EnlargedScanSource clamped(flat, {4, 4, 4}, {32, 32, 32}, 80.0, 7, 90, 110);
  for (float f : readAll(clamped)) ASSERT_TRUE(f >= 90.f && f <= 110.f) << f;
}

TEST(EnlargedScan, EstimatesTheNoiseOfAScan) {
  std::mt19937 rng(11);
  std::normal_distribution<float> noise(0.f, 3.f);
  const Index3 dims{40, 30, 20};
  std::vector<float> v;
  for (int z = 0; z < dims[2]; ++z)
    for (int y = 0; y < dims[1]; ++y)
      for (int x = 0; x < dims[0]; ++x) v.push_back(50.f + 0.2f * float(x + y) + noise(rng));
  EXPECT_NEAR(estimateScanNoise(v, dims), 3.0, 0.3);
}

TEST(EnlargedScan, RefusesWhatItCannotMake) {
  const std::vector<float> one(8, 1.f);
  EXPECT_THROW(EnlargedScanSource(one, {2, 2, 2}, {1, 8, 8}, 0, 1, 0, 1), InvalidArgument);
  EXPECT_THROW(EnlargedScanSource(one, {2, 2, 2}, {8, 8, 8}, -1, 1, 0, 1), InvalidArgument);
  EXPECT_THROW(EnlargedScanSource(one, {2, 2, 2}, {8, 8, 8}, std::nan(""), 1, 0, 1),
               InvalidArgument);
  EXPECT_THROW(EnlargedScanSource(one, {3, 2, 2}, {8, 8, 8}, 0, 1, 0, 1), InvalidArgument);
  EXPECT_THROW(EnlargedScanSource({}, {0, 2, 2}, {8, 8, 8}, 0, 1, 0, 1), InvalidArgument);
}

TEST(EnlargedScan, WrittenInTheSourceTypeRoundedAndClamped) {
  const float values[] = {-3.6f, -0.5f, 0.4f, 1.5f, 254.6f, 300.f};
  uint8_t u8[6];
  floatToSamples(SampleType::UInt8, values, 6, u8);
  EXPECT_EQ(std::vector<int>(u8, u8 + 6), (std::vector<int>{0, 0, 0, 2, 255, 255}));
  int16_t i16[6];
  floatToSamples(SampleType::Int16, values, 6, i16);
  EXPECT_EQ(std::vector<int>(i16, i16 + 6), (std::vector<int>{-4, 0, 0, 2, 255, 300}));
  float back[6];
  samplesToFloat(SampleType::Int16, i16, 6, back);
  EXPECT_EQ(back[5], 300.f);
  double lo, hi;
  sampleTypeRange(SampleType::Int16, lo, hi);
  EXPECT_EQ(lo, -32768.0);
  EXPECT_EQ(hi, 32767.0);
  float f32[6];
  floatToSamples(SampleType::Float32, values, 6, f32);
  EXPECT_EQ(f32[0], -3.6f);
}
