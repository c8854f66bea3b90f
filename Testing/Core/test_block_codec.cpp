// SPDX-License-Identifier: BSD-3-Clause
// block_codec: every value within step/2 of its reconstruction, decode equals the encoder's
// reconstruction bit for bit, in both forms of each predictor; the integer forms are chosen only
// where the values fit them and code no larger than the double forms; damaged coded bytes give a
// FormatError, never a crash.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/encode/encoder.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/format/block_codec.hpp"
#include "afam/format/rounded_points.hpp"
#include "scratch_dir.hpp"

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

/// Of 2000 copies of a coded payload, each with one byte after its header flipped (and every third
/// truncated as well), how many decodeValues refuses with a FormatError.
int refusedAmongDamaged(const std::vector<uint8_t>& bytes, size_t header, Int3 n, unsigned seed) {
  std::vector<float> out(static_cast<size_t>(n[0]) * size_t(n[1]) * size_t(n[2]));
  std::mt19937 rng(seed);
  int refused = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<uint8_t> b = bytes;
    const size_t at = std::uniform_int_distribution<size_t>(header, b.size() - 1)(rng);
    b[at] = uint8_t(b[at] ^ uint8_t(1 + trial % 255));
    if (trial % 3 == 0) b.resize(std::uniform_int_distribution<size_t>(0, b.size())(rng));
    try {
      decodeValues(b.data(), b.size(), n, out.data(), "x");
    } catch (const FormatError&) {
      ++refused;
    }
  }
  return refused;
}

}  // namespace

TEST(BlockCodec, ReconstructionWithinHalfAStepAndDecodedBitForBit) {
  const Int3 sizes[] = {{1, 1, 1}, {2, 3, 5}, {17, 1, 9}, {33, 33, 33}, {7, 40, 2}};
  for (const Int3& n : sizes)
    for (const Predictor p : {Predictor::Lorenzo, Predictor::Interpolation,
                              Predictor::IntegerLorenzo, Predictor::IntegerInterpolation})
      for (const double step : {1e-3, 0.05, 3.0}) {
        SCOPED_TRACE(std::to_string(n[0]) + "x" + std::to_string(n[1]) + "x" +
                     std::to_string(n[2]) + " p" + std::to_string(int(p)) + " step " +
                     std::to_string(step));
        const std::vector<float> v = field(n, unsigned(n[0] * 7 + n[2]));
        std::vector<uint8_t> bytes;
        std::vector<float> recon, viaQuantize, decoded(v.size());
        ASSERT_TRUE(encodeValues(v.data(), n, step, p, EntropyCoding{9}, bytes, recon));
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
  ASSERT_TRUE(
      encodeValues(v.data(), n, 0.2, Predictor::Interpolation, EntropyCoding{9}, bytes, recon));
  EXPECT_LT(bytes.size() * 8, v.size() * 4) << "under 4 bits a value at a step of 4 noise sigmas";
}

TEST(BlockCodec, AbsurdStepsAndDamagedBytesAreRefused) {
  const Int3 n{9, 9, 9};
  const std::vector<float> v = field(n, 9);
  std::vector<uint8_t> bytes;
  std::vector<float> recon, out(v.size());
  EXPECT_FALSE(encodeValues(v.data(), n, 0.0, Predictor::Lorenzo, EntropyCoding{3}, bytes, recon));
  EXPECT_FALSE(encodeValues(v.data(), n, 1e-30, Predictor::Lorenzo, EntropyCoding{3}, bytes, recon))
      << "codes beyond 2^50";
  ASSERT_TRUE(
      encodeValues(v.data(), n, 0.01, Predictor::Interpolation, EntropyCoding{3}, bytes, recon));
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
  EXPECT_GT(refusedAmongDamaged(bytes, kCodedHeaderBytes, n, 1), 1000)
      << "zstd's frame checks catch most damage; the checksum in the file catches the rest";
}

TEST(BlockCodec, IntegerFormsAreChosenWhereTheyFitAndCodeNoLargerThanDoubleForms) {
  const Int3 n{40, 33, 21};
  const std::vector<float> v = field(n, 5);
  const size_t count = v.size();
  for (const double step : {0.02, 0.2}) {
    for (const Predictor family : {Predictor::Lorenzo, Predictor::Interpolation}) {
      const Predictor form = choosePredictorForm(v.data(), count, step, family);
      EXPECT_TRUE(isIntegerForm(form));
      std::vector<uint8_t> dbl, integer;
      std::vector<float> r1, r2;
      ASSERT_TRUE(encodeValues(v.data(), n, step, family, EntropyCoding{9}, dbl, r1));
      ASSERT_TRUE(encodeValues(v.data(), n, step, form, EntropyCoding{9}, integer, r2));
      // Interpolation at a step of 4 noise sigmas is the exception: its integer form rounds the
      // predictions' fractions away and codes about 10% larger (the encoder keeps the smaller
      // form, block_encoding.cpp); everywhere else the forms code alike.
      if (family == Predictor::Interpolation && step > 0.1)
        EXPECT_LE(double(integer.size()), 1.15 * double(dbl.size()));
      else
        EXPECT_LE(double(integer.size()), 1.03 * double(dbl.size()))
            << "step " << step << " predictor " << int(family);
    }
  }
  // A spread of 2^27 steps does not fit: the double form is kept, and an integer form refuses.
  std::vector<float> wide = v;
  wide[7] = 100.0f + float(1 << 27) * 0.001f;
  EXPECT_EQ(choosePredictorForm(wide.data(), count, 0.001, Predictor::Interpolation),
            Predictor::Interpolation);
  std::vector<uint8_t> bytes;
  std::vector<float> recon;
  EXPECT_FALSE(encodeValues(wide.data(), n, 0.001, Predictor::IntegerLorenzo, EntropyCoding{3},
                            bytes, recon));
  EXPECT_TRUE(bytes.empty());
  EXPECT_TRUE(
      encodeValues(wide.data(), n, 0.001, Predictor::Lorenzo, EntropyCoding{3}, bytes, recon));
  // Values far from zero fit through the base: 1e6 + small variations at a step of 1e-3.
  std::vector<float> offset(count);
  for (size_t i = 0; i < count; ++i) offset[i] = 1e6f + 0.25f * float(i % 17);
  EXPECT_EQ(choosePredictorForm(offset.data(), count, 1e-3, Predictor::Lorenzo),
            Predictor::IntegerLorenzo);
  ASSERT_TRUE(encodeValues(offset.data(), n, 1e-3, Predictor::IntegerLorenzo, EntropyCoding{3},
                           bytes, recon));
  std::vector<float> decoded(count);
  decodeValues(bytes.data(), bytes.size(), n, decoded.data(), "offset");
  EXPECT_EQ(decoded, recon);
  for (size_t i = 0; i < count; ++i) ASSERT_NEAR(decoded[i], offset[i], 0.0626) << i;
  const float nan = std::nanf("");
  std::vector<float> holed = v;
  holed[3] = nan;
  EXPECT_EQ(choosePredictorForm(holed.data(), count, 0.1, Predictor::Lorenzo), Predictor::Lorenzo);
}

TEST(BlockCodec, DamagedIntegerPayloadsAreRefusedByName) {
  const Int3 n{19, 12, 10};
  const std::vector<float> v = field(n, 4);
  std::vector<float> out(v.size()), recon;
  for (const Predictor p : {Predictor::IntegerLorenzo, Predictor::IntegerInterpolation}) {
    std::vector<uint8_t> bytes;
    ASSERT_TRUE(encodeValues(v.data(), n, 0.01, p, EntropyCoding{3}, bytes, recon));
    std::vector<uint8_t> b = bytes;
    const int64_t hugeBase = int64_t(1) << 60;
    std::memcpy(b.data() + 9, &hugeBase, 8);
    try {
      decodeValues(b.data(), b.size(), n, out.data(), "blk");
      ADD_FAILURE() << "a base beyond 2^52 was accepted";
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find("blk: coded payload has an invalid base"),
                std::string::npos)
          << e.what();
    }
    EXPECT_THROW(decodeValues(bytes.data(), kIntegerCodedHeaderBytes, n, out.data(), "x"),
                 FormatError);
    // A frame of valid varints whose sums leave the range an encoder writes.
    std::vector<float> big(v.size(), 0.0f);
    big[0] = float(1 << 25) * 0.01f;
    big[1] = -float(1 << 25) * 0.01f;
    std::vector<uint8_t> edge;
    ASSERT_TRUE(encodeValues(big.data(), n, 0.01, p, EntropyCoding{3}, edge, recon));
    decodeValues(edge.data(), edge.size(), n, out.data(), "edge");
    EXPECT_EQ(out, recon) << "the widest spread that fits decodes";
    EXPECT_GT(refusedAmongDamaged(bytes, kIntegerCodedHeaderBytes, n, unsigned(p) * 31), 1000)
        << "predictor " << int(p);
  }
}

TEST(BlockCodec, FreeValuesKeepTheValidOnesAndStayWithinTheirSlackOfTheFilling) {
  // A ball of free values (a block's holes, filled here with a far-off constant, as no filling
  // should be): the valid values keep half a step whatever the slack; a free value is either its
  // own prediction (code 0) or kept like a valid one, and with a finite slack it stays within
  // slack + 1/2 steps of its filling; decoding gives the encoder's reconstruction bit for bit.
  const Int3 n{21, 18, 15};
  std::vector<float> v = field(n, 11);
  std::vector<uint32_t> valid(size_t((v.size() + 31) / 32), 0u);
  size_t i = 0, holes = 0;
  for (int z = 0; z < n[2]; ++z)
    for (int y = 0; y < n[1]; ++y)
      for (int x = 0; x < n[0]; ++x, ++i) {
        if ((x - 10) * (x - 10) + (y - 9) * (y - 9) + (z - 7) * (z - 7) < 36) {
          v[i] = 500.f;
          ++holes;
        } else {
          valid[i >> 5] |= 1u << (i & 31);
        }
      }
  ASSERT_GT(holes, 500u);
  const double step = 0.05;
  for (const Predictor p : {Predictor::Interpolation, Predictor::IntegerInterpolation})
    for (const int64_t slack : {int64_t(0), int64_t(16), FreeValues::kAnySlack}) {
      SCOPED_TRACE(std::to_string(int(p)) + " slack " + std::to_string(slack));
      std::vector<uint8_t> bytes;
      std::vector<float> recon, decoded(v.size()), quantized;
      const FreeValues free{valid.data(), slack};
      ASSERT_TRUE(encodeValues(v.data(), n, step, p, EntropyCoding{3}, bytes, recon, free));
      ASSERT_TRUE(quantizeValues(v.data(), n, step, p, quantized, free));
      EXPECT_EQ(0, std::memcmp(recon.data(), quantized.data(), recon.size() * 4));
      decodeValues(bytes.data(), bytes.size(), n, decoded.data(), "free");
      EXPECT_EQ(0, std::memcmp(recon.data(), decoded.data(), recon.size() * 4));
      double worstValid = 0, worstFree = 0;
      for (size_t k = 0; k < v.size(); ++k) {
        const double d = std::fabs(double(recon[k]) - double(v[k]));
        double& worst = free.isFree(int64_t(k)) ? worstFree : worstValid;
        worst = std::max(worst, d);
      }
      const double rounding = 1e-4;  // float32 near 500
      EXPECT_LE(worstValid, step / 2 + rounding);
      if (slack < FreeValues::kAnySlack) {
        EXPECT_LE(worstFree, (double(slack) + 0.5) * step + rounding);
      } else {
        EXPECT_GT(worstFree, 50 * step);  // free everywhere: the predictions, not the filling
      }
    }
}

TEST(BlockCodec, AKeptQuantizationCodesAndEstimatesAsTheValuesDo) {
  // An encoder's step ladder keeps the passing step's quantization and codes it without
  // quantizing again: after a buffer held another step, its estimate (whose codes may be sorted,
  // at a tiny step) and then its coding give what estimateCodedBytes and encodeValues give.
  const Int3 n{19, 14, 11};
  const std::vector<float> v = field(n, 3u);
  std::vector<uint32_t> valid(size_t((v.size() + 31) / 32), 0x5f5f5f5fu);
  for (const Predictor p : {Predictor::Lorenzo, Predictor::Interpolation, Predictor::IntegerLorenzo,
                            Predictor::IntegerInterpolation})
    for (const double step : {0.01, 1e-5})
      for (const bool withFree : {false, true}) {
        SCOPED_TRACE(std::to_string(int(p)) + " step " + std::to_string(step) +
                     (withFree ? " free" : ""));
        const FreeValues free = withFree ? FreeValues{valid.data(), 16} : FreeValues{};
        QuantizedValues q;
        ASSERT_TRUE(quantizeValues(v.data(), n, 0.3, p, q, free));
        ASSERT_TRUE(quantizeValues(v.data(), n, step, p, q, free));
        EXPECT_EQ(estimateCodedBytes(v.data(), n, step, p, free), estimateQuantizedBytes(q));
        std::vector<uint8_t> kept, direct;
        std::vector<float> recon;
        encodeQuantized(q, EntropyCoding{3}, kept);
        ASSERT_TRUE(encodeValues(v.data(), n, step, p, EntropyCoding{3}, direct, recon, free));
        EXPECT_EQ(direct, kept);
        EXPECT_EQ(recon, std::vector<float>(q.reconstructed.begin(), q.reconstructed.end()));
      }
}

TEST(BlockCodec, RecodingAFrameGivesThePayloadCodedAtTheOtherLevel) {
  // An encoder compares candidates coded at a fast zstd level and codes the kept one again at
  // the file's: the same bytes as coding it at the file's level directly, the same values, the
  // rounded-points byte after the frame kept.
  const Int3 n{33, 20, 9};
  const std::vector<float> v = field(n, 5u);
  for (const Predictor p : {Predictor::Lorenzo, Predictor::IntegerInterpolation})
    for (const EntropyStage stage : {EntropyStage::Auto, EntropyStage::Zstd}) {
      SCOPED_TRACE(std::to_string(int(p)) + " stage " + entropyStageName(stage));
      std::vector<uint8_t> fast, slow;
      std::vector<float> recon;
      ASSERT_TRUE(encodeValues(v.data(), n, 0.01, p, EntropyCoding{1, stage}, fast, recon));
      ASSERT_TRUE(encodeValues(v.data(), n, 0.01, p, EntropyCoding{15, stage}, slow, recon));
      const size_t head = codedHeaderBytes(fast.data(), fast.size());
      fast.push_back(7);  // a trailing byte, as a rounded interpolant's shift
      recodeFrame(fast, head, 1, v.size(), EntropyCoding{15, stage});
      ASSERT_EQ(fast.back(), 7);
      fast.pop_back();
      EXPECT_EQ(fast, slow);
      std::vector<float> decoded(v.size());
      decodeValues(fast.data(), fast.size(), n, decoded.data(), "recoded");
      EXPECT_EQ(decoded, recon);
    }
  std::vector<uint8_t> header(kCodedHeaderBytes, 0);
  EXPECT_THROW(recodeFrame(header, kCodedHeaderBytes, 0, 8, EntropyCoding{}), FormatError);
}

TEST(BlockCodec, ALorenzoFormJudgedUnableToWinCodesToAtLeastItsShareOfTheIntegerForm) {
  // lorenzoFormCannotWin judges from the integer form's trial frames and both forms' order-0
  // estimates, without coding the Lorenzo form: wherever it says that form cannot win, the form
  // coded must not come under kDoubleFormShare of the integer form's payload. It must judge some
  // value sets (noisy ones, whose lanes frames win) and leave the ones where the Lorenzo form wins.
  int judged = 0, lorenzoWon = 0;
  std::mt19937 rng(17u);
  for (const Int3 n : {Int3{6, 5, 4}, Int3{16, 16, 12}, Int3{33, 33, 33}})
    for (const double sigma : {0.0, 0.5, 2.0})
      for (const double step : {0.25, 1.0, 4.0, 16.0}) {
        SCOPED_TRACE(std::to_string(n[0]) + " sigma " + std::to_string(sigma) + " step " +
                     std::to_string(step));
        std::vector<float> v = field(n, 3u);
        std::normal_distribution<double> g(0, sigma > 0 ? sigma : 1);
        if (sigma > 0)
          for (float& x : v) x = float(x + g(rng));
        QuantizedValues integer, lorenzo, buffer;
        ASSERT_TRUE(quantizeValues(v.data(), n, step, Predictor::IntegerLorenzo, integer));
        ASSERT_TRUE(quantizeValues(v.data(), n, step, Predictor::Lorenzo, lorenzo));
        std::vector<uint8_t> payload, other;
        const FrameSizes trial = encodeQuantized(integer, EntropyCoding{1}, payload);
        encodeQuantized(lorenzo, EntropyCoding{1}, other);
        const bool won = double(other.size()) < kDoubleFormShare * double(payload.size());
        lorenzoWon += won;
        if (lorenzoFormCannotWin(integer, payload, trial, v.data(), buffer)) {
          ++judged;
          EXPECT_FALSE(won) << other.size() << " against " << payload.size();
        }
        // Only an IntegerLorenzo quantization is judged.
        EXPECT_FALSE(lorenzoFormCannotWin(lorenzo, payload, trial, v.data(), buffer));
      }
  EXPECT_GE(judged, 6);      // 11 of the 36 sets
  EXPECT_GE(lorenzoWon, 2);  // 4: the small blocks, whose header the Lorenzo form spares
}

TEST(BlockCodec, RecodingWithTheTrialsFramesGivesTheSameBytes) {
  // The frames' sizes of the trial coding spare work only: the lanes frame is not formed again.
  // Of the frames lanesFrameSure keeps, white noise's (codes of a few bits, where zstd's Huffman
  // spends nearly a bit on the likeliest) is the frame zstd at level 15 gives too; a smooth
  // periodic field at a coarse step is one it would not keep (its codes repeat, zstd's matches
  // code them), which is why the encoder asks it of noise-dominated blocks only.
  const Int3 n{40, 40, 40};
  std::vector<float> noise(static_cast<size_t>(n[0]) * size_t(n[1]) * size_t(n[2]));
  std::mt19937 rng(9u);
  std::normal_distribution<double> g(100, 1);
  for (float& x : noise) x = float(g(rng));
  int sureNoise = 0, sureSmoothLost = 0;
  for (const bool isNoise : {false, true})
    for (const Predictor p : {Predictor::Lorenzo, Predictor::IntegerInterpolation})
      for (const double step : {0.002, 0.05, 1.0, 3.0}) {
        SCOPED_TRACE(std::to_string(int(p)) + " step " + std::to_string(step));
        const std::vector<float> v = isNoise ? noise : field(n, 5u);
        QuantizedValues q;
        ASSERT_TRUE(quantizeValues(v.data(), n, step, p, q));
        std::vector<uint8_t> fast, slow;
        const FrameSizes trial = encodeQuantized(q, EntropyCoding{1}, fast);
        encodeQuantized(q, EntropyCoding{15}, slow);
        const size_t head = codedHeaderBytes(fast.data(), fast.size());
        const bool lanes = payloadIsLanesCoded(fast.data(), fast.size());
        EXPECT_GT(trial.zstd, 0u);
        EXPECT_EQ(lanes ? trial.lanes : trial.zstd, fast.size() - head);
        const bool sure = lanesFrameSure(trial, fast.size() - head, v.size());
        EXPECT_EQ(sure, lanes && double(trial.lanes) <= kLanesSure * double(trial.zstd));
        if (sure && isNoise) {
          ++sureNoise;
          EXPECT_EQ(fast, slow);
        }
        if (sure && !isNoise && fast != slow) ++sureSmoothLost;
        recodeFrame(fast, head, 0, v.size(), EntropyCoding{15}, trial);
        EXPECT_EQ(fast, slow);
      }
  EXPECT_GE(sureNoise, 2);
  EXPECT_GE(sureSmoothLost, 1);
}

TEST(BlockCodec, ANoisyBlocksSureLanesFrameIsTheOneTheSlowLevelGives) {
  // The encoder keeps a noise-dominated block's coded samples in their lanes frame without trying
  // zstd at the file's level where lanesFrameSure says it cannot win: the payload it writes is
  // the one coding its frame again at that level gives.
  const Index3 dims{40, 40, 40};
  std::mt19937 rng(9);
  std::normal_distribution<double> normal(0, 1);
  std::vector<float> noise(size_t(dims[0] * dims[1] * dims[2]));
  for (float& x : noise) x = float(normal(rng));
  EncoderOptions opt;
  opt.errorBound = 0.5;
  opt.levels = 1;
  opt.blocksPerAxis = 1;
  opt.threads = 1;
  ArraySource source(noise.data(), dims);
  const std::string path = afam_test::scratchPath("noise.afam");
  encodeVolume(source, opt, path);
  const auto file = AfamFile::open(path);
  const ModelEntry& m = file->entries()[0];
  ASSERT_EQ(m.kind, BlockKind::Interpolant);
  const std::vector<uint8_t> stored = file->readStored(0);
  const size_t head = codedHeaderBytes(stored.data(), stored.size());
  const size_t tail = m.roundedPoints ? kRoundedPointsBytes : 0;
  const size_t frame = stored.size() - head - tail, values = noise.size();
  ASSERT_TRUE(payloadIsLanesCoded(stored.data(), stored.size()));
  std::vector<uint8_t> fast = stored;  // the trial's zstd frame, for the rule's sizes
  recodeFrame(fast, head, tail, values, EntropyCoding{1, EntropyStage::Zstd});
  EXPECT_TRUE(lanesFrameSure(FrameSizes{fast.size() - head - tail, frame}, frame, values));
  std::vector<uint8_t> slow = stored;
  recodeFrame(slow, head, tail, values, EntropyCoding{});
  EXPECT_EQ(slow, stored);
}

TEST(BlockCodec, TheIntegerFormsQuantizeEveryValueToItsNearestStepTiesToEven) {
  // 17 x 241 values (not a multiple of the four a vector takes): ties, negatives, noise.
  const Int3 n{17, 241, 1};
  const size_t count = size_t(n[0]) * size_t(n[1]);
  const double step = 0.25;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> noise(-300.0f, 500.0f);
  std::vector<float> v(count);
  for (size_t i = 0; i < count; ++i)
    v[i] = i % 3 == 0 ? float((double(int(rng() % 4001) - 2000) + 0.5) * step) : noise(rng);
  QuantizedValues q;
  ASSERT_TRUE(quantizeValues(v.data(), n, step, Predictor::IntegerLorenzo, q));
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  const double middle = std::nearbyint((double(*lo) + double(*hi)) / 2 / step);
  EXPECT_EQ(q.base, int64_t(middle));
  size_t ties = 0;
  for (size_t i = 0; i < count; ++i) {
    const double x = double(v[i]) / step;
    ties += x - std::floor(x) == 0.5;
    ASSERT_EQ(q.k[i], int32_t(std::nearbyint(x) - middle)) << "value " << i << " = " << v[i];
    ASSERT_EQ(q.reconstructed[i], float((middle + double(q.k[i])) * step)) << "value " << i;
  }
  EXPECT_GT(ties, count / 4);
  // A value the codes cannot hold fails the block, in a vector's lanes or in the tail.
  for (const size_t at : {size_t(5), count - 2}) {
    std::vector<float> w = v;
    w[at] = float(std::ldexp(step, 27));
    EXPECT_FALSE(quantizeValues(w.data(), n, step, Predictor::IntegerLorenzo, q)) << "at " << at;
  }
}
