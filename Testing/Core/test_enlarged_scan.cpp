// SPDX-License-Identifier: BSD-3-Clause
// EnlargedScanSource: a small volume resampled to any size with noise at the new resolution.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>
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

/// A 6x5x4 source of random values in 0..199.
std::vector<float> randomSource(unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<float> src(6 * 5 * 4);
  for (float& f : src) f = float(rng() % 200);
  return src;
}

/// Reads `s` in slabs of `planes` planes, the last slab first, and expects the values of `all`.
void expectTheSameInSlabs(EnlargedScanSource& s, const std::vector<float>& all, int64_t planes) {
  const Index3 d = s.dims();
  const size_t plane = size_t(d[0] * d[1]);
  std::vector<float> slab(plane * size_t(planes));
  for (int64_t z0 = (d[2] - 1) / planes * planes; z0 >= 0; z0 -= planes) {
    const int64_t nz = std::min(planes, d[2] - z0);
    s.readSlab(z0, nz, slab.data());
    for (size_t i = 0; i < plane * size_t(nz); ++i)
      ASSERT_EQ(slab[i], all[size_t(z0) * plane + i]) << z0;
  }
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
  const std::vector<float> src = randomSource(3);
  const Index3 big{13, 11, 9};
  EnlargedScanSource whole(src, {6, 5, 4}, big, 4.0, 42, 0, 255);
  const std::vector<float> all = readAll(whole);
  EnlargedScanSource cut(src, {6, 5, 4}, big, 4.0, 42, 0, 255);
  expectTheSameInSlabs(cut, all, 1);
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

namespace {

/// Variance of `v` (n^3, x fastest) and of its means over blocks of b^3 voxels.
std::pair<double, double> varianceAndBlockVariance(const std::vector<float>& v, int64_t n,
                                                   int64_t b) {
  double sum = 0, sq = 0;
  for (float f : v) {
    sum += f;
    sq += double(f) * f;
  }
  const double mean = sum / double(v.size());
  std::vector<double> blocks(size_t((n / b) * (n / b) * (n / b)), 0.0);
  for (int64_t z = 0; z < n; ++z)
    for (int64_t y = 0; y < n; ++y)
      for (int64_t x = 0; x < n; ++x)
        blocks[size_t(((z / b) * (n / b) + y / b) * (n / b) + x / b)] +=
            v[size_t((z * n + y) * n + x)] / double(b * b * b);
  double bsq = 0;
  for (double m : blocks) bsq += (m - mean) * (m - mean);
  return {sq / double(v.size()) - mean * mean, bsq / double(blocks.size())};
}

}  // namespace

TEST(EnlargedScan, DetailHasTheAskedDeviationAndEnergyAtCoarseScales) {
  const std::vector<float> flat(4 * 4 * 4, 100.f);
  const int64_t n = 128;
  EnlargedScanSource s(flat, {4, 4, 4}, {n, n, n}, 0.0, 5, -1e9, 1e9);
  s.setDetail(6.0);
  const auto [var, blockVar] = varianceAndBlockVariance(readAll(s), n, 16);
  EXPECT_NEAR(std::sqrt(var), 6.0, 0.6) << "the detail's standard deviation is --detail";
  EXPECT_GT(blockVar / var, 0.1) << "16^3 block means keep a tenth of the detail's variance";
  EnlargedScanSource white(flat, {4, 4, 4}, {n, n, n}, 6.0, 5, -1e9, 1e9);
  const auto [wvar, wblockVar] = varianceAndBlockVariance(readAll(white), n, 16);
  EXPECT_LT(wblockVar / wvar, 0.002) << "white noise averages away: the test tells them apart";
}

TEST(EnlargedScan, DetailStaysOutOfTheAir) {
  // Air (0) below z = 4 of 8 source planes, tissue (200) above: the detail is whole in the
  // tissue and absent from the air, beyond the two source samples the interpolation reaches.
  std::vector<float> half(8 * 8 * 8, 0.f);
  std::fill(half.begin() + 8 * 8 * 4, half.end(), 200.f);
  const int64_t n = 64;
  EnlargedScanSource s(half, {8, 8, 8}, {n, n, n}, 0.0, 3, -1e9, 1e9);
  s.setDetail(10.0);
  const std::vector<float> v = readAll(s);
  double airWorst = 0, tissueSq = 0;
  int64_t tissue = 0;
  for (int64_t z = 0; z < n; ++z)
    for (int64_t i = 0; i < n * n; ++i) {
      const double x = v[size_t(z * n * n + i)];
      if (z < 14) airWorst = std::max(airWorst, std::fabs(x));
      if (z > 50) {
        tissueSq += (x - 200) * (x - 200);
        ++tissue;
      }
    }
  EXPECT_EQ(airWorst, 0.0) << "the air took detail";
  EXPECT_NEAR(std::sqrt(tissueSq / double(tissue)), 10.0, 3.0) << "the tissue's detail";
}

TEST(EnlargedScan, TissueNoiseInTheTissueAndTheAirsOwnInTheAir) {
  // Air (0) below z = 4 of 8 source planes, tissue (200) above, the air's noise 2, the tissue's 6.
  std::vector<float> half(8 * 8 * 8, 0.f);
  std::fill(half.begin() + 8 * 8 * 4, half.end(), 200.f);
  const int64_t n = 64;
  EnlargedScanSource s(half, {8, 8, 8}, {n, n, n}, 2.0, 3, -1e9, 1e9);
  EnlargedScanSource same = s;
  s.setTissueNoise(6.0);
  const std::vector<float> v = readAll(s);
  double airSq = 0, tissueSq = 0;
  int64_t air = 0, tissue = 0;
  for (int64_t z = 0; z < n; ++z)
    for (int64_t i = 0; i < n * n; ++i) {
      const double x = v[size_t(z * n * n + i)];
      if (z < 14) {
        airSq += x * x;
        ++air;
      } else if (z > 50) {
        tissueSq += (x - 200) * (x - 200);
        ++tissue;
      }
    }
  EXPECT_NEAR(std::sqrt(airSq / double(air)), 2.0, 0.05) << "the air keeps --noise";
  EXPECT_NEAR(std::sqrt(tissueSq / double(tissue)), 6.0, 0.15) << "the tissue's --tissue-noise";
  const std::vector<float> plain = readAll(same);
  same.setTissueNoise(2.0);
  EXPECT_EQ(readAll(same), plain) << "the air's noise everywhere: the bytes without it";
  for (double bad : {-1.0, std::nan(""), double(INFINITY)})
    EXPECT_THROW(same.setTissueNoise(bad), InvalidArgument) << bad;
}

TEST(EnlargedScan, DetailIsTheSameHoweverTheVolumeIsCut) {
  const std::vector<float> src = randomSource(5);
  const Index3 big{37, 29, 41};
  EnlargedScanSource whole(src, {6, 5, 4}, big, 2.0, 9, 0, 255);
  whole.setDetail(8.0, 1.0);
  const std::vector<float> all = readAll(whole);
  EnlargedScanSource cut(src, {6, 5, 4}, big, 2.0, 9, 0, 255);
  cut.setDetail(8.0, 1.0);
  expectTheSameInSlabs(cut, all, 3);
  EnlargedScanSource plain(src, {6, 5, 4}, big, 2.0, 9, 0, 255), zero = plain;
  zero.setDetail(0.0);
  EXPECT_EQ(readAll(zero), readAll(plain)) << "--detail 0 leaves the bytes as they were";
  EXPECT_NE(readAll(plain), all);
  EnlargedScanSource otherSeed(src, {6, 5, 4}, big, 2.0, 10, 0, 255);
  otherSeed.setDetail(8.0, 1.0);
  EXPECT_NE(readAll(otherSeed), all) << "the seed changes the detail";
}

TEST(EnlargedScan, RefusesBadDetail) {
  EnlargedScanSource s(std::vector<float>(8, 1.f), {2, 2, 2}, {8, 8, 8}, 0, 1, 0, 1);
  for (double bad : {-1.0, std::nan(""), double(INFINITY)}) {
    try {
      s.setDetail(bad);
      ADD_FAILURE() << bad << " accepted";
    } catch (const InvalidArgument& e) {
      EXPECT_STREQ(e.what(), "the detail must be finite and >= 0");
    }
  }
  EXPECT_THROW(s.setDetail(1.0, -0.5), InvalidArgument);
  EXPECT_THROW(s.setDetail(1.0, 4.0), InvalidArgument);
  EXPECT_THROW(s.setDetail(1.0, std::nan("")), InvalidArgument);
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
