// SPDX-License-Identifier: BSD-3-Clause
// Missing samples (issue 30): NaN or a fill value marks them; the encoder keeps the bound on the
// valid samples of every level, stores a block's mask compactly and a block with no valid sample
// as empty; readers give NaN exactly where the input (or a coarse level's majority) misses; the
// file is smaller than the same volume with its holes filled by hand; bad input is named.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/encode/encode_run.hpp"
#include "afam/encode/encoder.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/format/block_decode.hpp"
#include "afam/format/block_mask.hpp"
#include "afam/format/step_extract.hpp"
#include "afam/render/level_decode.hpp"
#include "afam/sampling/block_sampling.hpp"
#include "afam/volume/masked_volumes.hpp"
#include "afam/volume/missing_value_source.hpp"
#include "moving_blob.hpp"
#include "scratch_dir.hpp"

using namespace afam;

namespace {

const Index3 kDims{48, 44, 40};
const float kNaN = std::numeric_limits<float>::quiet_NaN();

EncoderOptions options(BoundKind kind, double bound) {
  EncoderOptions opt;
  opt.levels = 2;
  opt.blocksPerAxis = 3;
  opt.errorBound = bound;
  opt.relativeBound = true;
  opt.boundKind = kind;
  opt.threads = 2;
  return opt;
}

/// What one file's blocks do against the samples they were fitted to.
struct Check {
  int64_t maskMismatches = 0, missing = 0, valid = 0;
  double worstRmse = 0, worstError = 0;  ///< over blocks, on valid samples
};

/// Every block of every level decoded on its sample grid against the source's samples of it (the
/// encoder's sampling rule): NaN at the same places, and the error of the valid ones.
Check checkEveryBlock(const AfamFile& f, VolumeSource& source) {
  Check c;
  const Partition& part = f.partition();
  BlockRowReader reader(source, part);
  std::vector<std::vector<float>> row;
  std::vector<float> decoded;
  for (int l = 0; l < part.levels(); ++l) {
    const Int3 nb = part.blocksPerAxis(l);
    for (int kz = 0; kz < nb[2]; ++kz) {
      reader.readRow(l, kz, false, f.header().sampling, row);
      for (int j = 0; j < nb[1]; ++j)
        for (int i = 0; i < nb[0]; ++i) {
          const int64_t e = f.entryIndex(l, {i, j, kz});
          const std::vector<float> payload = f.readPayload(e);
          decodeBlockSamples(f.entries()[size_t(e)], payload.data(), f.header().mode, decoded);
          const std::vector<float>& truth = row[size_t(j * nb[0] + i)];
          double sum = 0, worst = 0;
          int64_t used = 0;
          for (size_t s = 0; s < truth.size(); ++s) {
            if (std::isnan(truth[s]) || std::isnan(decoded[s])) {
              ++(std::isnan(truth[s]) == std::isnan(decoded[s]) ? c.missing : c.maskMismatches);
              continue;
            }
            const double d = double(decoded[s]) - double(truth[s]);
            sum += d * d;
            worst = std::max(worst, std::fabs(d));
            ++used;
          }
          c.valid += used;
          if (used > 0) c.worstRmse = std::max(c.worstRmse, std::sqrt(sum / double(used)));
          c.worstError = std::max(c.worstError, worst);
        }
    }
  }
  return c;
}

std::vector<float> maskedVolume(MaskShape shape, float fill = kNaN) {
  std::vector<float> v = afam_test::movingBlob(kDims, 0);
  ArraySource inner(v.data(), kDims);
  const VolumeMask mask(shape, kDims);
  MaskedSource masked(inner, mask, fill);
  std::vector<float> out(v.size());
  masked.readSlab(0, kDims[2], out.data());
  return out;
}

std::vector<uint32_t> ballMask(Int3 n, double cx, double r) {
  std::vector<float> s(static_cast<size_t>(n[0]) * size_t(n[1]) * size_t(n[2]), 1.f);
  size_t i = 0;
  for (int z = 0; z < n[2]; ++z)
    for (int y = 0; y < n[1]; ++y)
      for (int x = 0; x < n[0]; ++x, ++i)
        if ((x - cx) * (x - cx) + (y - 10.0) * (y - 10.0) + (z - 12.0) * (z - 12.0) < r * r)
          s[i] = kNaN;
  return maskOfValid(s.data(), int64_t(s.size()));
}

}  // namespace

TEST(MissingValues, AMaskRoundTripsAndASmoothOneCodesInFewBytes) {
  const Int3 n{33, 30, 27};
  const int64_t count = int64_t(n[0]) * n[1] * n[2];
  for (double r : {0.5, 6.0, 14.0, 60.0}) {
    const std::vector<uint32_t> words = ballMask(n, 20.0, r);
    const std::vector<uint8_t> coded = encodeMask(words, n);
    std::vector<float> back(size_t(maskWordCount(count)));
    decodeMask(coded.data(), coded.size(), n, back.data(), "test");
    for (int64_t i = 0; i < count; ++i)
      ASSERT_EQ(maskBit(back.data(), i), ((words[size_t(i >> 5)] >> (i & 31)) & 1u) != 0)
          << "radius " << r << " sample " << i;
    // The words are 3.3 KB; inside and outside cost next to nothing, a ball's boundary about two
    // bits per boundary sample (measured 1.9 at radius 6).
    const double boundary = 4 * 3.14159 * r * r;
    EXPECT_LT(double(coded.size()), 32 + 2.5 * std::min(boundary, double(count)) / 8)
        << "radius " << r;
  }
  const std::vector<uint32_t> words = ballMask(n, 20.0, 9.0);
  std::vector<uint8_t> coded = encodeMask(words, n);
  std::vector<float> back(size_t(maskWordCount(count)));
  EXPECT_THROW(decodeMask(coded.data(), coded.size() - 3, n, back.data(), "cut"), FormatError);
  std::vector<uint8_t> longer = coded;
  longer.push_back(0);
  EXPECT_THROW(decodeMask(longer.data(), longer.size(), n, back.data(), "long"), FormatError);
}

TEST(MissingValues, EveryLevelKeepsTheBoundOnValidSamplesAndTheMaskExactly) {
  for (MaskShape shape : {MaskShape::Ball, MaskShape::Land, MaskShape::FieldOfView}) {
    const std::vector<float> v = maskedVolume(shape);
    ArraySource source(v.data(), kDims);
    for (BoundKind kind : {BoundKind::Rmse, BoundKind::MaxError})
      for (double rel : {1e-2, 1e-3}) {
        const std::string path = afam_test::scratchPath("missing.afam");
        const EncodeStats s = encodeVolume(source, options(kind, rel), path);
        auto f = AfamFile::open(path);
        EXPECT_EQ(f->version(), 3u);
        EXPECT_EQ(f->header().missing, MissingKind::NaN);
        const Check c = checkEveryBlock(*f, source);
        const std::string what = std::string(boundKindName(kind)) + " " + std::to_string(rel) +
                                 " shape " + std::to_string(int(shape));
        EXPECT_EQ(c.maskMismatches, 0) << what;
        EXPECT_GT(c.missing, 0) << what;
        EXPECT_GT(c.valid, c.missing / 4) << what;
        const double limit = s.bound * (1 + 1e-6);
        EXPECT_LE(kind == BoundKind::Rmse ? c.worstRmse : c.worstError, limit) << what;
      }
  }
}

TEST(MissingValues, ABlockWithNoValidSampleIsEmptyAndDecodesToNaN) {
  const std::vector<float> v = maskedVolume(MaskShape::FieldOfView);  // corners outside the circle
  ArraySource source(v.data(), kDims);
  EncoderOptions opt = options(BoundKind::Rmse, 1e-2);
  opt.levels = 1;
  opt.blocksPerAxis = 8;
  const std::string path = afam_test::scratchPath("empty.afam");
  encodeVolume(source, opt, path);
  auto f = AfamFile::open(path);
  int64_t empty = 0, masked = 0;
  for (size_t e = 0; e < f->entries().size(); ++e) {
    const ModelEntry& m = f->entries()[e];
    if (m.masked) ++masked;
    if (m.kind != BlockKind::Empty) continue;
    ++empty;
    EXPECT_EQ(m.storedSize, 0u);
    EXPECT_EQ(m.size, 0u);
    std::vector<float> decoded;
    decodeBlockSamples(m, nullptr, f->header().mode, decoded);
    ASSERT_FALSE(decoded.empty());
    for (float x : decoded) ASSERT_TRUE(std::isnan(x));
  }
  EXPECT_GE(empty, 4) << "the four corner columns of blocks lie outside the field of view";
  EXPECT_GT(masked, 8);
  EXPECT_EQ(checkEveryBlock(*f, source).maskMismatches, 0);
}

TEST(MissingValues, SmallerThanTheVolumeFilledWithTheNearestValidValue) {
  // Corpus volumes at their default partitions, holes as users meet them; the by-hand file keeps
  // its bound on the filled samples too (docs/BENCHMARKS.md "Missing values" has every volume and
  // bound).
  const std::string dir = std::string(AFAM_TEST_DATA_DIR) + "/volumes/";
  const struct {
    const char* name;
    SampleType type;
    Index3 dims;
    MaskShape shape;
  } cases[] = {
      {"neghip_66x66x66_uint8.raw", SampleType::UInt8, {66, 66, 66}, MaskShape::Ball},
      {"chi_field_50x50x50_float32.raw", SampleType::Float32, {50, 50, 50}, MaskShape::Land},
      {"headsq_quarter_64x64x93_int16.raw",
       SampleType::Int16,
       {64, 64, 93},
       MaskShape::FieldOfView}};
  for (const auto& c : cases) {
    RawFileSource raw(dir + c.name, c.dims, c.type);
    const VolumeMask mask(c.shape, c.dims);
    MaskedSource masked(raw, mask);
    std::vector<float> holes(size_t(c.dims[0] * c.dims[1] * c.dims[2]));
    masked.readSlab(0, c.dims[2], holes.data());
    std::vector<float> filled = holes;
    fillNearestValid(filled, c.dims);
    ArraySource a(holes.data(), c.dims), b(filled.data(), c.dims);
    for (BoundKind kind : {BoundKind::Rmse, BoundKind::MaxError})
      for (double bound : {1e-2, 1e-3}) {
        EncoderOptions opt = options(kind, bound);
        opt.levels = opt.blocksPerAxis = 0;
        const EncodeStats withHoles = encodeVolume(a, opt, afam_test::scratchPath("holes.afam"));
        const EncodeStats byHand = encodeVolume(b, opt, afam_test::scratchPath("filled.afam"));
        EXPECT_LE(withHoles.bytesOut, byHand.bytesOut)
            << c.name << " " << boundKindName(kind) << " " << bound;
      }
  }
}

TEST(MissingValues, AFillValueMarksMissingSamplesAsNaNDoes) {
  const std::vector<float> nan = maskedVolume(MaskShape::Ball);
  const std::vector<float> fill = maskedVolume(MaskShape::Ball, -999.f);
  ArraySource a(nan.data(), kDims), inner(fill.data(), kDims);
  MissingValueSource b(inner, -999.0);
  const std::string na = afam_test::scratchPath("nan.afam"),
                    nb = afam_test::scratchPath("fill.afam");
  encodeVolume(a, options(BoundKind::Rmse, 1e-2), na);
  EncoderOptions opt = options(BoundKind::Rmse, 1e-2);
  opt.hasMissingValue = true;
  opt.missingValue = -999.0;
  encodeVolume(b, opt, nb);
  EXPECT_GT(b.matches(), 0);
  auto fa = AfamFile::open(na), fb = AfamFile::open(nb);
  EXPECT_EQ(fb->header().missing, MissingKind::Value);
  EXPECT_EQ(fb->header().missingValue, -999.0);
  ASSERT_EQ(fa->entries().size(), fb->entries().size());
  for (size_t e = 0; e < fa->entries().size(); ++e) {  // bit for bit (mask words are no floats)
    const std::vector<float> pa = fa->readPayload(int64_t(e)), pb = fb->readPayload(int64_t(e));
    ASSERT_EQ(pa.size(), pb.size());
    EXPECT_EQ(std::memcmp(pa.data(), pb.data(), pa.size() * sizeof(float)), 0) << "entry " << e;
  }
}

TEST(MissingValues, BadInputIsNamed) {
  std::vector<float> none(size_t(kDims[0] * kDims[1] * kDims[2]), kNaN);
  ArraySource empty(none.data(), kDims);
  try {
    encodeVolume(empty, options(BoundKind::Rmse, 1e-2), afam_test::scratchPath("none.afam"));
    ADD_FAILURE() << "a volume without a valid sample was encoded";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("no valid sample"), std::string::npos) << e.what();
  }
  std::vector<float> v = maskedVolume(MaskShape::Ball);
  ArraySource holes(v.data(), kDims);
  EncoderOptions ds = options(BoundKind::Rmse, 1e-2);
  ds.mode = EncodingMode::Downsampled;
  EXPECT_THROW(encodeVolume(holes, ds, afam_test::scratchPath("ds.afam")), InvalidArgument);
  EXPECT_THROW(MissingValueSource(holes, std::nan("")), InvalidArgument);
  EXPECT_THROW(MissingValueSource(holes, 300.0, SampleType::UInt8), InvalidArgument);
  EXPECT_THROW(MissingValueSource(holes, 1.5, SampleType::Int16), InvalidArgument);
  EXPECT_NO_THROW(MissingValueSource(holes, -32768.0, SampleType::Int16));
}

TEST(MissingValues, AVolumeWithoutMissingSamplesIsWrittenAsBefore) {
  const std::vector<float> v = afam_test::movingBlob(kDims, 0);
  ArraySource source(v.data(), kDims);
  const std::string path = afam_test::scratchPath("whole.afam");
  encodeVolume(source, options(BoundKind::Rmse, 1e-2), path);
  auto f = AfamFile::open(path);
  EXPECT_EQ(f->version(), 2u);
  EXPECT_EQ(f->header().missing, MissingKind::None);
  for (const ModelEntry& m : f->entries()) {
    EXPECT_FALSE(m.masked);
    EXPECT_NE(m.kind, BlockKind::Empty);
  }
}

TEST(MissingValues, ARunWithHolesAtSomeStepsKeepsEveryStepsMaskAndCodesTheRestInTime) {
  // Step 0 whole, steps 1 and 2 with the same ball missing: the run declares missing samples from
  // its first step; masked blocks are coded on their own, the others still refer in time.
  const std::vector<float> whole = afam_test::movingBlob(kDims, 0);
  const std::vector<float> holes = maskedVolume(MaskShape::Ball);
  ArraySource s0(whole.data(), kDims), s1(holes.data(), kDims), s2(holes.data(), kDims);
  const std::string path = afam_test::scratchPath("run.afam");
  RunOptions run;
  run.keyInterval = 4;
  const RunStats stats = encodeRun({&s0, &s1, &s2}, options(BoundKind::Rmse, 1e-2), run, path);
  EXPECT_GT(stats.references[2], 0) << "step 2 repeats step 1: its blocks refer to it";
  for (int64_t step = 0; step < 3; ++step) {
    auto f = AfamFile::open(path, step);
    EXPECT_EQ(f->header().missing, MissingKind::NaN);
    int64_t masked = 0;
    for (const ModelEntry& m : f->entries()) {
      masked += m.masked;
      if (m.masked) {
        EXPECT_FALSE(m.reference || m.residual) << "step " << step;
      }
    }
    EXPECT_EQ(masked > 0, step > 0) << "step " << step;
    ArraySource truth(step == 0 ? whole.data() : holes.data(), kDims);
    const Check c = checkEveryBlock(*f, truth);
    EXPECT_EQ(c.maskMismatches, 0) << "step " << step;
    EXPECT_EQ(c.missing > 0, step > 0) << "step " << step;
    EXPECT_LE(c.worstRmse, stats.bound * (1 + 1e-6)) << "step " << step;
  }
  // A step extracted on its own keeps its holes (a version-3 file of one step) and decodes the
  // same.
  const std::string one = afam_test::scratchPath("step1.afam");
  extractStep(path, 1, one);
  auto alone = AfamFile::open(one), inRun = AfamFile::open(path, 1);
  EXPECT_EQ(alone->version(), 3u);
  EXPECT_EQ(alone->stepCount(), 1);
  EXPECT_EQ(alone->header().missing, MissingKind::NaN);
  const Index3 hi{kDims[0] - 1, kDims[1] - 1, kDims[2] - 1};
  std::vector<float> a(holes.size()), b(holes.size());
  decodeLevelBox(*alone, 1, {0, 0, 0}, hi, a.data());
  decodeLevelBox(*inRun, 1, {0, 0, 0}, hi, b.data());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0);
  EXPECT_EQ(checkEveryBlock(*alone, s1).maskMismatches, 0);
  // A run written without missing samples refuses a later step with some, by name.
  RunEncoder streaming(afam_test::scratchPath("streaming.afam"), options(BoundKind::Rmse, 1e-2), 4);
  streaming.addStep(s0, 0.0);
  try {
    streaming.addStep(s1, 1.0);
    ADD_FAILURE() << "a step with holes joined a run declared without";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("missing samples"), std::string::npos) << e.what();
  }
}
