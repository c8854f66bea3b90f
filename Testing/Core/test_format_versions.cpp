// SPDX-License-Identifier: BSD-3-Clause
// Format versions: a version-1 file written before version 2 still opens and decodes the same
// values; version-2 files carry mixed block kinds and survive damage to every structure.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "afam/encode/encoder.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/render/level_decode.hpp"

#include "file_bytes.hpp"
#include "scratch_dir.hpp"

using namespace afam;
using afam_test::readAll;
using afam_test::writeAll;

namespace {

const std::string kFormat = std::string(AFAM_TEST_DATA_DIR) + "/format/";

std::string scratch(const std::string& name) {
  return afam_test::scratchPath("afam_format_" + name);  // removed with its folder at exit
}

/// A small volume mixing every block kind: a constant half, a smooth quarter and a noisy quarter.
std::vector<float> mixedVolume(Index3& dims) {
  dims = {65, 40, 33};
  std::vector<float> v(size_t(dims[0] * dims[1] * dims[2]));
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1, 1);
  size_t i = 0;
  for (int64_t z = 0; z < dims[2]; ++z)
    for (int64_t y = 0; y < dims[1]; ++y)
      for (int64_t x = 0; x < dims[0]; ++x, ++i)
        v[i] = x < 32 ? 5.0f
                      : (y < 20 ? 5.0f + 3.0f * float(std::sin(0.2 * double(x + y + z)))
                                : 5.0f + u(rng));
  return v;
}

/// The options both version-2 tests encode the mixed volume with.
EncoderOptions mixedOptions() {
  EncoderOptions opt;
  opt.errorBound = 1e-2;
  opt.relativeBound = true;
  opt.levels = 2;
  opt.blocksPerAxis = 4;
  return opt;
}

}  // namespace

TEST(FormatVersions, VersionOneFileStillDecodesTheSameValues) {
  auto f = AfamFile::open(kFormat + "ml17_levels2_blocks2_v1.afam");
  EXPECT_EQ(f->version(), 1u);
  EXPECT_EQ(f->header().sampling, LevelSampling::Point);
  for (const ModelEntry& e : f->entries()) {
    EXPECT_EQ(e.kind, BlockKind::Spline);
    EXPECT_FALSE(e.coded);
    EXPECT_EQ(e.storedSize, e.size);
  }
  const Index3 dims = f->header().dims;
  ASSERT_EQ(dims, (Index3{17, 17, 17}));
  std::vector<float> decoded(size_t(17 * 17 * 17));
  decodeLevelBox(*f, 1, {0, 0, 0}, {16, 16, 16}, decoded.data());
  const std::vector<char> expected =
      readAll(kFormat + "ml17_levels2_blocks2_v1_level1_decoded_17x17x17_float32.raw");
  ASSERT_EQ(expected.size(), decoded.size() * sizeof(float));
  EXPECT_EQ(std::memcmp(expected.data(), decoded.data(), expected.size()), 0)
      << "version-1 decode changed";
}

TEST(FormatVersions, DoubleFormPayloadsWrittenBeforeTheIntegerFormsDecodeTheSameBytes) {
  auto f = AfamFile::open(kFormat + "mixed40_levels2_blocks2_v2_double.afam");
  int coded = 0;
  for (const ModelEntry& e : f->entries()) {
    EXPECT_FALSE(e.integerCoded);
    coded += e.coded;
  }
  EXPECT_EQ(coded, 9);
  const uint32_t expected[2] = {0x7f34152du, 0xc67b8005u};  // that version's afam decode
  for (int level = 0; level < 2; ++level) {
    const Index3 dims = level == 0 ? Index3{21, 21, 21} : Index3{40, 40, 40};
    std::vector<float> decoded(size_t(dims[0] * dims[1] * dims[2]));
    decodeLevelBox(*f, level, {0, 0, 0}, {dims[0] - 1, dims[1] - 1, dims[2] - 1}, decoded.data());
    EXPECT_EQ(crc32(decoded.data(), decoded.size() * sizeof(float)), expected[level])
        << "level " << level << " decodes differently from the double forms' reader";
  }
}

TEST(FormatVersions, ARunWithResidualsAndReferencesDecodesTheSameBytes) {
  const std::string path = kFormat + "gs24_run5_levels2_blocks2_v3.afam";
  const uint32_t expected[5] = {0xfd661dd3u, 0x7c0424adu, 0x7c0424adu, 0xfde4d4d6u, 0x6d4d14e1u};
  const int residuals[5] = {0, 9, 0, 9, 0}, references[5] = {0, 0, 9, 0, 0};
  for (int64_t s = 0; s < 5; ++s) {
    SCOPED_TRACE("step " + std::to_string(s));
    auto f = AfamFile::open(path, s);
    ASSERT_EQ(f->stepCount(), 5);
    int r = 0, refs = 0;
    uint32_t longest = 0;
    for (const ModelEntry& e : f->entries()) {
      r += e.residual && !e.reference;
      refs += e.reference;
      longest = std::max(longest, e.chainLength);
    }
    EXPECT_EQ(r, residuals[s]);
    EXPECT_EQ(refs, references[s]);
    EXPECT_EQ(longest, s == 3 ? 3u : s == 4 ? 1u : uint32_t(std::min<int64_t>(s, 1) + 1));
    std::vector<float> decoded(size_t(24 * 24 * 24));
    decodeLevelBox(*f, 1, {0, 0, 0}, {23, 23, 23}, decoded.data());
    EXPECT_EQ(crc32(decoded.data(), decoded.size() * sizeof(float)), expected[s]);
  }
}

TEST(FormatVersions, IntegerFormsAreFlaggedInTheIndexAndAMismatchIsRefused) {
  Index3 dims;
  const std::vector<float> v = mixedVolume(dims);
  ArraySource src(v.data(), dims);
  const std::string path = scratch("integer.afam");
  encodeVolume(src, mixedOptions(), path);
  std::vector<char> b = readAll(path);
  auto f = AfamFile::open(path);
  int64_t flagged = -1;
  for (size_t i = 0; i < f->entries().size(); ++i) {
    const ModelEntry& e = f->entries()[i];
    EXPECT_TRUE(e.coded || !e.integerCoded);
    if (e.integerCoded && flagged < 0) flagged = int64_t(i);
  }
  ASSERT_GE(flagged, 0);
  f.reset();
  // Clear bit 9 of that entry (index entry at 1024 + 40 i, flags at +14) and fix the index and
  // header checksums, as a writer that knew only the double forms would have flagged it.
  const size_t at = 1024 + 40 * size_t(flagged) + 14;
  b[at + 1] = char(b[at + 1] & ~0x02);
  uint64_t entries;
  std::memcpy(&entries, b.data() + 144, 8);
  const uint32_t indexCrc = crc32(b.data() + 1024, size_t(entries) * 40);
  std::memcpy(b.data() + 140, &indexCrc, 4);
  const uint32_t headerCrc = crc32(b.data(), 1020);
  std::memcpy(b.data() + 1020, &headerCrc, 4);
  const std::string bad = scratch("integer_unflagged.afam");
  writeAll(bad, b);
  auto g = AfamFile::open(bad);
  std::vector<float> out(g->entries()[size_t(flagged)].size / 4);
  try {
    g->readPayload(flagged, out.data());
    ADD_FAILURE() << "an integer-form payload under a double-form flag was decoded";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("disagrees with the index"), std::string::npos)
        << e.what();
  }
  std::remove(path.c_str());
  std::remove(bad.c_str());
}

TEST(FormatVersions, VersionTwoHoldsEveryKindAndRoundTrips) {
  Index3 dims;
  const std::vector<float> v = mixedVolume(dims);
  ArraySource src(v.data(), dims);
  const EncoderOptions opt = mixedOptions();
  InMemoryModels mem;
  const EncodeStats st = encodeVolume(src, opt, mem);
  const std::string path = scratch("mixed.afam");
  mem.write(path);
  auto f = AfamFile::open(path);
  EXPECT_EQ(f->version(), 2u);
  EXPECT_EQ(f->header().sampling, LevelSampling::Box);
  int kinds[4] = {0, 0, 0, 0};
  std::vector<float> payload;
  for (size_t i = 0; i < f->entries().size(); ++i) {
    const ModelEntry& e = f->entries()[i];
    ++kinds[int(e.kind)];
    EXPECT_EQ(e.storedSize, mem.entries[i].storedSize);
    payload.resize(e.size / 4);
    f->readPayload(int64_t(i), payload.data());
    EXPECT_EQ(payload, mem.payloads[i]) << "entry " << i << " decodes as in memory";
  }
  EXPECT_GT(kinds[int(BlockKind::Constant)], 0);
  EXPECT_GT(kinds[int(BlockKind::Spline)] + kinds[int(BlockKind::Interpolant)], 0);
  int64_t counted = 0;
  for (const LevelStats& ls : st.levels)
    counted += ls.kinds[0] + ls.kinds[1] + ls.kinds[2] + ls.kinds[3];
  EXPECT_EQ(counted, int64_t(f->entries().size()));
  std::remove(path.c_str());
}

TEST(FormatVersions, VersionTwoDamageIsRefusedNamingTheBlock) {
  Index3 dims;
  const std::vector<float> v = mixedVolume(dims);
  ArraySource src(v.data(), dims);
  const EncoderOptions opt = mixedOptions();
  const std::string path = scratch("damage.afam");
  encodeVolume(src, opt, path);
  const std::vector<char> good = readAll(path);
  const std::string bad = scratch("damage_bad.afam");
  std::mt19937 rng(5);
  int refusedOpen = 0, refusedRead = 0, accepted = 0;
  for (int trial = 0; trial < 400; ++trial) {
    std::vector<char> b = good;
    if (trial % 4 == 0) {
      b.resize(std::uniform_int_distribution<size_t>(0, b.size() - 1)(rng));  // truncation anywhere
    } else {
      const size_t at = std::uniform_int_distribution<size_t>(0, b.size() - 1)(rng);
      b[at] = char(b[at] ^ char(1 + trial % 255));
    }
    writeAll(bad, b);
    try {
      auto f = AfamFile::open(bad);
      std::vector<float> out;
      for (size_t i = 0; i < f->entries().size(); ++i) {
        out.resize(f->entries()[i].size / 4);
        f->readPayload(int64_t(i), out.data());
      }
      ++accepted;  // a flip inside padding or an unused header byte
    } catch (const FormatError& e) {
      const std::string w = e.what();
      EXPECT_NE(w.find(bad), std::string::npos) << w;
      if (w.find("block (") != std::string::npos)
        ++refusedRead;
      else
        ++refusedOpen;
    }
  }
  EXPECT_GT(refusedOpen, 50);
  EXPECT_GT(refusedRead, 20) << "payload damage names the block";
  EXPECT_LT(accepted, 40);
  std::remove(path.c_str());
  std::remove(bad.c_str());
}
