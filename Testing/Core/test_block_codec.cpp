// SPDX-License-Identifier: BSD-3-Clause
// block_codec: every value within step/2 of its reconstruction, decode equals the encoder's
// reconstruction bit for bit, and damaged coded bytes give a FormatError, never a crash.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/format/block_codec.hpp"

using namespace afam;

namespace {

std::vector<float> field(Int3 n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, 0.05);
  std::vector<float> v(static_cast<size_t>(n[0]) * size_t(n[1]) * size_t(n[2]));
  size_t i = 0;
  for (int z = 0; z < n[2]; ++z)
    for (int y = 0; y < n[1]; ++y)
      for (int x = 0; x < n[0]; ++x)
        v[i++] = float(100 + 20 * std::sin(0.3 * x) * std::cos(0.2 * (y - z)) + g(rng));
  return v;
}

}  // namespace

TEST(BlockCodec, ReconstructionWithinHalfAStepAndDecodedBitForBit) {
  const Int3 sizes[] = {{1, 1, 1}, {2, 3, 5}, {17, 1, 9}, {33, 33, 33}, {7, 40, 2}};
  for (const Int3& n : sizes)
    for (const Predictor p : {Predictor::Lorenzo, Predictor::Interpolation})
      for (const double step : {1e-3, 0.05, 3.0}) {
        SCOPED_TRACE(std::to_string(n[0]) + "x" + std::to_string(n[1]) + "x" +
                     std::to_string(n[2]) + " p" + std::to_string(int(p)) + " step " +
                     std::to_string(step));
        const std::vector<float> v = field(n, unsigned(n[0] * 7 + n[2]));
        std::vector<uint8_t> bytes;
        std::vector<float> recon, viaQuantize, decoded(v.size());
        ASSERT_TRUE(encodeValues(v.data(), n, step, p, 9, bytes, recon));
        ASSERT_TRUE(quantizeValues(v.data(), n, step, p, viaQuantize));
        EXPECT_EQ(recon, viaQuantize);
        double worst = 0;
        for (size_t i = 0; i < v.size(); ++i)
          worst = std::max(worst, std::fabs(double(recon[i]) - double(v[i])));
        EXPECT_LE(worst, 0.5 * step * (1 + 1e-6) + 1e-4) << "float rounding of ~100 adds 1e-5";
        decodeValues(bytes.data(), bytes.size(), n, decoded.data(), "test");
        EXPECT_EQ(decoded, recon);
        const double est = estimateCodedBytes(v.data(), n, step, p);
        EXPECT_GT(est, 0.0);
      }
}

TEST(BlockCodec, SmoothDataCodesFarBelowFloats) {
  const Int3 n{33, 33, 33};
  const std::vector<float> v = field(n, 3);
  std::vector<uint8_t> bytes;
  std::vector<float> recon;
  ASSERT_TRUE(encodeValues(v.data(), n, 0.2, Predictor::Interpolation, 9, bytes, recon));
  EXPECT_LT(bytes.size() * 8, v.size() * 4) << "under 4 bits a value at a step of 4 noise sigmas";
}

TEST(BlockCodec, AbsurdStepsAndDamagedBytesAreRefused) {
  const Int3 n{9, 9, 9};
  const std::vector<float> v = field(n, 9);
  std::vector<uint8_t> bytes;
  std::vector<float> recon, out(v.size());
  EXPECT_FALSE(encodeValues(v.data(), n, 0.0, Predictor::Lorenzo, 3, bytes, recon));
  EXPECT_FALSE(encodeValues(v.data(), n, 1e-30, Predictor::Lorenzo, 3, bytes, recon))
      << "codes beyond 2^50";
  ASSERT_TRUE(encodeValues(v.data(), n, 0.01, Predictor::Interpolation, 3, bytes, recon));
  std::vector<uint8_t> b = bytes;
  b[8] = 7;
  EXPECT_THROW(decodeValues(b.data(), b.size(), n, out.data(), "x"), FormatError);
  b = bytes;
  const double nan = std::nan("");
  std::memcpy(b.data(), &nan, 8);
  EXPECT_THROW(decodeValues(b.data(), b.size(), n, out.data(), "x"), FormatError);
  EXPECT_THROW(decodeValues(bytes.data(), 5, n, out.data(), "x"), FormatError);
  EXPECT_THROW(decodeValues(bytes.data(), bytes.size(), Int3{9, 9, 10}, out.data(), "x"),
               FormatError);
  std::mt19937 rng(1);
  int refused = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    b = bytes;
    const size_t at = std::uniform_int_distribution<size_t>(kCodedHeaderBytes, b.size() - 1)(rng);
    b[at] = uint8_t(b[at] ^ uint8_t(1 + trial % 255));
    if (trial % 3 == 0) b.resize(std::uniform_int_distribution<size_t>(0, b.size())(rng));
    try {
      decodeValues(b.data(), b.size(), n, out.data(), "x");
    } catch (const FormatError&) {
      ++refused;
    }
  }
  EXPECT_GT(refused, 1000)
      << "zstd's frame checks catch most damage; the checksum in the file catches the rest";
}
