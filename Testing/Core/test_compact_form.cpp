// SPDX-License-Identifier: BSD-3-Clause
// The compact form of decoded models (compact_form.hpp): an integer-coded payload's values kept as
// a table and a 1- or 2-byte code each, read back as the very floats decodeValues gives
// (test_compact_frames.cpp: the cache and the frames).
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/format/block_codec.hpp"

using namespace afam;

namespace {

/// Values uniform in [0, range) on an n^3 grid, coded with step 1 by an integer predictor.
std::vector<uint8_t> codedUniform(int n, double range, Predictor p, std::vector<float>& decoded) {
  std::vector<float> v(size_t(n) * n * n);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, range);
  for (float& x : v) x = float(u(rng));
  std::vector<uint8_t> out;
  EXPECT_TRUE(encodeValues(v.data(), {n, n, n}, 1.0, p, EntropyCoding{}, out, decoded));
  return out;
}

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

}  // namespace

TEST(CompactForm, CodesReadThroughTheTableAreTheDecodedFloats) {
  const int n = 24;
  const size_t count = size_t(n) * n * n;
  struct Case {
    double range;
    Predictor predictor;
    int width;
  };
  for (const Case c :
       {Case{200, Predictor::IntegerLorenzo, 1}, Case{250, Predictor::IntegerInterpolation, 1},
        Case{3000, Predictor::IntegerLorenzo, 2},
        Case{60000, Predictor::IntegerInterpolation, 0},  // table too large
        Case{200000, Predictor::IntegerLorenzo, 0}}) {    // codes wider than 16 bits
    std::vector<float> want, got;
    const std::vector<uint8_t> coded = codedUniform(n, c.range, c.predictor, want);
    const CompactForm f =
        decodeValuesCompact(coded.data(), coded.size(), {n, n, n}, 0.75, got, "test");
    ASSERT_EQ(f.width, c.width) << c.range;
    if (f.width == 0) {
      ASSERT_EQ(got.size(), count);
      for (size_t i = 0; i < count; ++i) ASSERT_TRUE(sameBits(got[i], want[i])) << i;
      continue;
    }
    EXPECT_GE(f.table, uint32_t(c.range * 0.9));
    EXPECT_LE(f.table, uint32_t(c.range + 2));
    EXPECT_EQ(got.size(), f.table + (count * size_t(f.width) + 3) / 4);
    std::vector<float> expanded(count);
    expandCompact(got.data(), f, count, expanded.data());
    for (size_t i = 0; i < count; ++i)
      ASSERT_TRUE(sameBits(expanded[i], want[i])) << c.range << " at " << i;
  }
  // Asked for a form at most a tenth of the floats: a 1-byte code is a quarter, so floats.
  std::vector<float> want, got;
  const std::vector<uint8_t> coded = codedUniform(n, 200, Predictor::IntegerLorenzo, want);
  EXPECT_EQ(decodeValuesCompact(coded.data(), coded.size(), {n, n, n}, 0.1, got, "t").width, 0);
  EXPECT_EQ(got.size(), count);
}

TEST(CompactForm, ADamagedPayloadIsRefusedAsByDecodeValues) {
  const int n = 16;
  std::vector<float> decoded, out(size_t(n) * n * n), compact;
  std::vector<uint8_t> coded = codedUniform(n, 200, Predictor::IntegerLorenzo, decoded);
  coded.resize(coded.size() - 7);  // its frame cut short
  std::string plain, mine;
  try {
    decodeValues(coded.data(), coded.size(), {n, n, n}, out.data(), "payload");
  } catch (const FormatError& e) {
    plain = e.what();
  }
  try {
    decodeValuesCompact(coded.data(), coded.size(), {n, n, n}, 0.75, compact, "payload");
  } catch (const FormatError& e) {
    mine = e.what();
  }
  EXPECT_FALSE(plain.empty());
  EXPECT_EQ(mine, plain);
}
