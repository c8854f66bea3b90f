// SPDX-License-Identifier: BSD-3-Clause
// Interpolants with rounded control points (rounded_points.hpp): the encoder rounds a noisy scan's
// interpolants where the bound allows, every point a reader decodes is a multiple of the payload's
// point step, each block still meets the bound, a cache keeps them in 1- or 2-byte codes with the
// very same frame, and a damaged flag or step is refused.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "afam/base/thread_scratch.hpp"
#include "afam/encode/encoder.hpp"
#include "afam/format/rounded_points.hpp"
#include "afam/render/renderer.hpp"
#include "afam/spline/fit.hpp"
#include "afam/volume/enlarged_scan.hpp"
#include "file_bytes.hpp"
#include "head_mri.hpp"
#include "render_test_util.hpp"

using namespace afam;

namespace {

/// The repository's head MRI made twice as large with noise well above the bound (6 units against
/// 1e-2 of the range, 2.55): its finest blocks are coded as interpolants.
EnlargedScanSource noisyHead() {
  std::vector<float> v = afam_test::headMri();
  return EnlargedScanSource(std::move(v), {48, 62, 42}, {96, 124, 84}, 6.0, 1, 0, 255);
}

std::shared_ptr<const AfamFile> noisyHeadFile() {
  const std::string path = afam_test::tempPath("rounded_points_head");
  if (::access(path.c_str(), R_OK) != 0) {
    EnlargedScanSource src = noisyHead();
    EncoderOptions o;
    o.errorBound = 1e-2;
    o.relativeBound = true;
    o.levels = 2;  // 64 finest blocks, and a coarse level whose averaged noise fits splines
    o.blocksPerAxis = 4;
    o.threads = 2;
    encodeVolume(src, o, path);
  }
  return AfamFile::open(path);
}

/// The samples of block `e` of the finest level, x fastest.
std::vector<float> blockSamples(const std::vector<float>& volume, Index3 dims,
                                const BlockExtent& e) {
  std::vector<float> s;
  for (int64_t z = e.lo[2]; z <= e.hi[2]; ++z)
    for (int64_t y = e.lo[1]; y <= e.hi[1]; ++y)
      for (int64_t x = e.lo[0]; x <= e.hi[0]; ++x)
        s.push_back(volume[size_t((z * dims[1] + y) * dims[0] + x)]);
  return s;
}

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

}  // namespace

namespace {
/// visit(index, entry, compact form, its values) for each interpolant with rounded points, its
/// compact form as a cache reads it (at most 0.75 of its floats, else width 0).
template <typename Visit>
void forEachRoundedCompact(const AfamFile& file, Visit&& visit) {
  for (size_t i = 0; i < file.entries().size(); ++i) {
    const ModelEntry& e = file.entries()[i];
    if (!e.roundedPoints) continue;
    std::vector<float> form;
    const CompactForm f = file.readCompact(int64_t(i), 0.75, form);
    visit(i, e, f, form);
  }
}
}  // namespace

TEST(RoundedPoints, ANoisyScansInterpolantsAreRoundedWithinTheBound) {
  const auto file = noisyHeadFile();
  EnlargedScanSource src = noisyHead();
  const Index3 dims = src.dims();
  std::vector<float> volume(size_t(dims[0] * dims[1] * dims[2]));
  src.readSlab(0, dims[2], volume.data());
  const double bound = absoluteBound(file->header());
  const int finest = file->header().levels - 1;
  int64_t interpolants = 0, rounded = 0;
  BlockFitter fitter;
  for (size_t i = 0; i < file->entries().size(); ++i) {
    const ModelEntry& e = file->entries()[i];
    interpolants += e.kind == BlockKind::Interpolant;
    if (!e.roundedPoints) continue;
    ++rounded;
    EXPECT_EQ(e.kind, BlockKind::Interpolant);
    const std::vector<uint8_t> stored = file->readStored(int64_t(i));
    const double q = roundedPointStep(stored.data(), stored.size(), "test");
    FitResult model;
    model.ncp = e.ncp;
    model.degree = e.degree;
    model.control = file->readPayload(int64_t(i));
    for (const float c : model.control)  // each point a multiple of q, as the reader keeps it
      ASSERT_TRUE(sameBits(c, pointValue(pointCode(c, q), q))) << c << " at step " << q;
    if (e.level != finest) continue;
    const std::vector<float> s =
        blockSamples(volume, dims, file->partition().extent(e.level, e.block));
    const ErrorStats err = fitter.error(s.data(), e.samples, model);
    EXPECT_LE(err.rmse, bound) << Partition::blockName(e.level, e.block);
    // The index tells the rounded model's error as a reader decodes it (kept in float32), which
    // the encoder measured on these bytes' decoding without decoding the stored payload again.
    EXPECT_NEAR(err.rmse, e.rmse, 1e-5 * bound);
  }
  ASSERT_GE(interpolants, 32);
  EXPECT_GE(rounded, interpolants * 3 / 4) << rounded << " of " << interpolants;
}

TEST(RoundedPoints, TheCacheKeepsThemInCodesAndDrawsTheSameFrame) {
  const auto file = noisyHeadFile();
  int64_t compact = 0, rounded = 0;
  forEachRoundedCompact(*file, [&](size_t i, const ModelEntry&, const CompactForm& f,
                                   const std::vector<float>& form) {
    ++rounded;
    const std::vector<float> floats = file->readPayload(int64_t(i));
    if (f.width == 0) return;
    ++compact;
    std::vector<float> expanded(floats.size());
    expandCompact(form.data(), f, floats.size(), expanded.data());
    for (size_t k = 0; k < floats.size(); ++k)
      ASSERT_TRUE(sameBits(expanded[k], floats[k])) << "entry " << i << " point " << k;
  });
  EXPECT_EQ(compact, rounded);
  // Drawn from codes, the frame is the floats' frame, from under half the bytes.
  const afam_test::CompactAndFloats c = afam_test::drawCompactAndFloats(file, 60, 48);
  EXPECT_EQ(c.compactBlocks, c.floatBlocks);
  EXPECT_LT(2 * c.compactBytes, c.floatBytes) << c.compactBytes << " vs " << c.floatBytes;
}

TEST(RoundedPoints, DecodingOneForTheCacheHoldsTwoBlocksOfScratch) {
  // The cache's byte budget counts the decoding scratch (thread_scratch.hpp): a rounded
  // interpolant's compact form is decoded through its samples (4 bytes a point, then its points in
  // the same place) and, in the double form, decodeValues' doubles (8 bytes a point, then its codes
  // in the same place), its frame and stored bytes: about 13.5 bytes a point, where four buffers
  // took 25.5; the integer forms' two word buffers (8 bytes a point) come beside the codes: 21.5,
  // where they took 25.5.
  const auto file = noisyHeadFile();
  size_t checked = 0, doubleForms = 0;
  for (size_t i = 0; i < file->entries().size(); ++i) {
    const ModelEntry& e = file->entries()[i];
    if (!e.roundedPoints) continue;
    uint64_t held = 0;
    std::vector<float> compact;
    std::thread([&] {  // a thread of its own: only this decoding's scratch
      const uint64_t before = threadScratchBytes();
      file->readCompact(int64_t(i), 0.5, compact);
      held = threadScratchBytes() - before;
      releaseAllThreadScratch();
    })
        .join();
    const uint64_t points = uint64_t(controlCount(e)), words = e.integerCoded ? 8 : 0;
    EXPECT_LE(held, (14 + words) * points + 2 * e.storedSize + 4096)
        << Partition::blockName(e.level, e.block) << (e.integerCoded ? ", integer form" : "");
    EXPECT_GE(held, (12 + words) * points);
    ++checked;
    doubleForms += !e.integerCoded;
  }
  EXPECT_GT(checked, 8u);
  EXPECT_GT(doubleForms, 4u);
}

TEST(RoundedPoints, ADamagedFlagOrShiftIsRefused) {
  const auto file = noisyHeadFile();
  int64_t rounded = -1;
  for (size_t i = 0; i < file->entries().size() && rounded < 0; ++i)
    if (file->entries()[i].roundedPoints) rounded = int64_t(i);
  ASSERT_GE(rounded, 0);
  const std::string bad = afam_test::tempPath("rounded_points_damaged");
  auto error = [&](const std::vector<char>& b, int64_t read) {
    afam_test::writeAll(bad, b);
    try {
      auto g = AfamFile::open(bad);
      if (read >= 0) g->readPayload(read);
    } catch (const FormatError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  // Bit 14 on a spline's entry (Marschner-Lobb's blocks are splines): refused at open.
  const auto ml = afam_test::encodeMl(33, EncodingMode::Adaptive);
  int64_t spline = -1;
  for (size_t i = 0; i < ml->entries().size() && spline < 0; ++i)
    if (ml->entries()[i].kind == BlockKind::Spline) spline = int64_t(i);
  ASSERT_GE(spline, 0);
  std::vector<char> b = afam_test::readAll(ml->path());
  uint16_t flags;
  std::memcpy(&flags, &b[1024 + 40 * size_t(spline) + 14], 2);
  flags |= uint16_t(1u << 14);
  afam_test::patchIndex(b, size_t(spline), 14, &flags, 2);
  std::string w = error(b, -1);
  EXPECT_NE(w.find("rounded points flagged on a spline"), std::string::npos) << w;
  // A shift past the largest (its payload's CRC made right): refused when the model is read.
  b = afam_test::readAll(file->path());
  const ModelEntry& e = file->entries()[size_t(rounded)];
  b[e.offset + e.storedSize - 1] = char(kMaxPointShift + 1);
  const uint32_t crc = crc32(&b[e.offset], e.storedSize);
  afam_test::patchIndex(b, size_t(rounded), 32, &crc, 4);
  w = error(b, rounded);
  EXPECT_NE(w.find("point step"), std::string::npos) << w;
  EXPECT_NE(w.find(Partition::blockName(e.level, e.block)), std::string::npos) << w;
  std::remove(bad.c_str());
}

TEST(RoundedPoints, TheSpanOfTheirCodesIsThatOfRoundPointsCodes) {
  // roundPointsSpan (the encoder's trial of a step) rounds as roundPoints does and gives the span
  // of the codes roundPoints writes; a point it cannot round fails both.
  std::mt19937 rng(11);
  std::normal_distribution<float> value(40.f, 300.f);
  for (const double q : {0.5, 0.0625, 3.0}) {
    std::vector<float> a(10007);
    for (float& v : a) v = value(rng);
    std::vector<float> b = a;
    std::vector<int64_t> k(a.size());
    ASSERT_TRUE(roundPoints(a.data(), a.size(), q, k.data()));
    uint64_t span = 0;
    ASSERT_TRUE(roundPointsSpan(b.data(), b.size(), q, span));
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0) << q;
    const auto [lo, hi] = std::minmax_element(k.begin(), k.end());
    EXPECT_EQ(span, uint64_t(*hi - *lo)) << q;
    EXPECT_GT(span, uint64_t(1000 / q)) << q;  // ~+-4 sigma of 300 in steps of q
  }
  std::vector<float> bad = {1.f, std::numeric_limits<float>::quiet_NaN(), 2.f};
  uint64_t span = 7;
  EXPECT_FALSE(roundPointsSpan(bad.data(), bad.size(), 0.5, span));
  EXPECT_EQ(span, 0u);
}

TEST(RoundedPoints, AFieldWhoseSamplesComeNearTheBoundKeepsCodesOfUnderHalfItsFloats) {
  // The field GpuCompactModels draws (noise three times the bound): many of its blocks' samples
  // come within 0.5% of the bound, where the walk from the first shift finds a step whose codes
  // take 1 or 2 bytes (a search guided by the rounding's gain stopped at shift 7 in two of them,
  // codes four times wider, and the cache held more than half the floats).
  const auto file = afam_test::encodeNoisyField(EntropyStage::Auto, 0.03);
  uint64_t compactBytes = 0, floatBytes = 0;
  int64_t rounded = 0;
  forEachRoundedCompact(*file, [&](size_t i, const ModelEntry& e, const CompactForm& f,
                                   const std::vector<float>& form) {
    ++rounded;
    EXPECT_GT(f.width, 0) << "entry " << i;
    compactBytes += form.size() * sizeof(float);
    floatBytes += e.size;
  });
  ASSERT_GE(rounded, 32);
  EXPECT_LT(2 * compactBytes, floatBytes) << compactBytes << " vs " << floatBytes;
}
