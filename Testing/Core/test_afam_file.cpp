// SPDX-License-Identifier: BSD-3-Clause
// .afam container: round trips, every corrupt-file case, atomic writes.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <dirent.h>
#include <atomic>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/format/afam_file.hpp"
#include "file_bytes.hpp"
#include "scratch_dir.hpp"

using namespace afam;

namespace {

std::string tempDir() { return afam_test::scratchDir(); }

std::vector<char> readAll(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::vector<char>((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}
void writeAll(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(bytes.data(), std::streamsize(bytes.size()));
}

VolumeHeader smallHeader(EncodingMode mode = EncodingMode::Adaptive) {
  VolumeHeader h;
  h.dims = {20, 17, 9};
  h.origin = {1, 2, 3};
  h.spacing = {0.5, 0.25, 2};
  h.valueMin = -1;
  h.valueMax = 3;
  h.scalarName = "density";
  h.levels = 2;
  h.blocksPerAxis = 4;
  h.degree = 2;
  h.errorBound = 1e-3;
  h.relativeBound = true;
  h.mode = mode;
  return h;
}

// Deterministic models for every block of the header's partition; NCP varies per block.
struct Models {
  std::vector<ModelEntry> entries;
  std::vector<std::vector<float>> payloads;
};
Models makeModels(const VolumeHeader& h) {
  Partition p(h.dims, h.levels, h.blocksPerAxis);
  Models m;
  std::mt19937 rng(7);
  for (int l = 0; l < h.levels; ++l)
    for (int64_t li = 0; li < p.blockCount(l); ++li) {
      ModelEntry e;
      e.level = l;
      e.block = p.blockFromLinear(l, li);
      const auto ext = p.extent(l, e.block);
      e.samples = ext.samples;
      for (int a = 0; a < 3; ++a) {
        if (h.mode == EncodingMode::Downsampled) {
          e.ncp[a] = ext.samples[a] + 2;
          e.degree[a] = 1;
        } else {
          e.degree[a] = std::min(h.degree, ext.samples[a] - 1);
          const int lo = e.degree[a] + 1, hi = ext.samples[a];
          e.ncp[a] = lo + int(rng() % unsigned(hi - lo + 1));
        }
      }
      e.minValue = float(l);
      e.maxValue = float(li);
      e.rmse = 1e-4f * float(li);
      e.maxError = 2e-4f;
      std::vector<float> pl(size_t(e.ncp[0]) * e.ncp[1] * e.ncp[2]);
      for (size_t i = 0; i < pl.size(); ++i) pl[i] = float(l * 1000 + li) + 0.001f * float(i);
      m.entries.push_back(e);
      m.payloads.push_back(std::move(pl));
    }
  return m;
}

std::string writeFile(const std::string& name, const VolumeHeader& h, const Models& m,
                      bool reverse = false) {
  const std::string path = tempDir() + "/" + name;
  AfamWriter w(path, h);
  for (size_t k = 0; k < m.entries.size(); ++k) {
    const size_t i = reverse ? m.entries.size() - 1 - k : k;
    w.add(m.entries[i], m.payloads[i].data());
  }
  w.commit();
  return path;
}

template <typename Fn>
std::string expectFormatError(const std::string& path, Fn&& corrupt) {
  auto bytes = readAll(path);
  corrupt(bytes);
  const std::string bad = path + ".bad";
  writeAll(bad, bytes);
  try {
    auto f = AfamFile::open(bad);
    // Opening may succeed when only a payload is damaged: reading every payload must then fail.
    std::vector<float> buf;
    for (size_t i = 0; i < f->entries().size(); ++i) {
      buf.resize(f->entries()[i].size / 4);
      f->readPayload(int64_t(i), buf.data());
    }
  } catch (const FormatError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(bad), std::string::npos) << "message names the file: " << what;
    return what;
  }
  ADD_FAILURE() << "no FormatError";
  return "";
}

size_t countTempFiles(const std::string& dir, const std::string& prefix) {
  size_t n = 0;
  DIR* d = opendir(dir.c_str());
  if (!d) return 0;
  while (dirent* e = readdir(d))
    if (std::string(e->d_name).rfind(prefix, 0) == 0) ++n;
  closedir(d);
  return n;
}

}  // namespace

TEST(AfamFile, Crc32KnownValue) {
  EXPECT_EQ(crc32("123456789", 9), 0xCBF43926u);
  EXPECT_EQ(crc32("", 0), 0u);
  // Incremental == one shot, across the 8-byte fast path.
  const std::string s = "The quick brown fox jumps over the lazy dog";
  EXPECT_EQ(crc32(s.data() + 5, s.size() - 5, crc32(s.data(), 5)), crc32(s.data(), s.size()));
  EXPECT_EQ(crc32(s.data(), s.size()), 0x414FA339u);
}

TEST(AfamFile, PaperLayoutSize) {
  // 1 + ((NCP + p) * 3 + NCP^3) * 4 for cubic NCP.
  EXPECT_EQ(paperModelBytes({10, 10, 10}, {2, 2, 2}), 1u + (12u * 3u + 1000u) * 4u);
  EXPECT_EQ(payloadBytes({10, 10, 10}), 4000u);
  EXPECT_LT(payloadBytes({3, 3, 3}), paperModelBytes({3, 3, 3}, {2, 2, 2}));
}

TEST(AfamFile, RoundTripAnyOrder) {
  for (EncodingMode mode :
       {EncodingMode::Adaptive, EncodingMode::Fixed, EncodingMode::Downsampled}) {
    const VolumeHeader h = smallHeader(mode);
    const Models m = makeModels(h);
    for (bool reverse : {false, true}) {
      const std::string path = writeFile(
          std::string("rt_") + modeName(mode) + (reverse ? "_rev" : "") + ".afam", h, m, reverse);
      auto f = AfamFile::open(path);
      EXPECT_EQ(f->path(), path);
      const VolumeHeader& g = f->header();
      EXPECT_EQ(g.dims, h.dims);
      EXPECT_EQ(g.origin, h.origin);
      EXPECT_EQ(g.spacing, h.spacing);
      EXPECT_EQ(g.valueMin, h.valueMin);
      EXPECT_EQ(g.valueMax, h.valueMax);
      EXPECT_EQ(g.scalarName, h.scalarName);
      EXPECT_EQ(g.levels, h.levels);
      EXPECT_EQ(g.blocksPerAxis, h.blocksPerAxis);
      EXPECT_EQ(g.degree, h.degree);
      EXPECT_EQ(g.errorBound, h.errorBound);
      EXPECT_EQ(g.relativeBound, h.relativeBound);
      EXPECT_EQ(g.mode, h.mode);
      ASSERT_EQ(f->entries().size(), m.entries.size());
      EXPECT_EQ(f->payloadOffset() % 64, 0u);
      for (size_t i = 0; i < m.entries.size(); ++i) {
        const ModelEntry& a = m.entries[i];
        const int64_t idx = f->entryIndex(a.level, a.block);
        ASSERT_EQ(idx, int64_t(i));
        const ModelEntry& b = f->entries()[size_t(idx)];
        EXPECT_EQ(b.ncp, a.ncp);
        EXPECT_EQ(b.degree, a.degree);
        EXPECT_EQ(b.samples, a.samples);
        EXPECT_EQ(b.rmse, a.rmse);
        EXPECT_EQ(b.maxValue, a.maxValue);
        EXPECT_EQ(b.offset % 4, 0u) << "payloads aligned for float32";
        EXPECT_EQ(b.size, m.payloads[i].size() * 4);
        const std::vector<float> back = f->readPayload(idx);
        EXPECT_EQ(back, m.payloads[i]);
      }
      EXPECT_EQ(f->entryIndex(-1, {0, 0, 0}), -1);
      EXPECT_EQ(f->entryIndex(2, {0, 0, 0}), -1);
      EXPECT_EQ(f->entryIndex(0, {5, 0, 0}), -1);
      EXPECT_EQ(f->entryIndex(1, {0, -1, 0}), -1);
    }
  }
}

TEST(AfamFile, WriterRejectsBadAdds) {
  const VolumeHeader h = smallHeader();
  const Models m = makeModels(h);
  const std::string path = tempDir() + "/reject.afam";
  AfamWriter w(path, h);
  w.add(m.entries[0], m.payloads[0].data());
  EXPECT_THROW(w.add(m.entries[0], m.payloads[0].data()), InvalidArgument);  // twice
  ModelEntry e = m.entries[1];
  e.block = {99, 0, 0};
  EXPECT_THROW(w.add(e, m.payloads[1].data()), InvalidArgument);
  e = m.entries[1];
  e.ncp[0] = e.samples[0] + 1;
  EXPECT_THROW(w.add(e, m.payloads[1].data()), InvalidArgument);
  e = m.entries[1];
  e.samples[0] += 1;
  EXPECT_THROW(w.add(e, m.payloads[1].data()), InvalidArgument);
  EXPECT_THROW(w.commit(), InvalidArgument);  // blocks missing
}

TEST(AfamFile, AtomicWriteLeavesNothingWithoutCommit) {
  const VolumeHeader h = smallHeader();
  const Models m = makeModels(h);
  const std::string dir = tempDir() + "/atomic";
  mkdir(dir.c_str(), 0755);
  const std::string path = dir + "/out.afam";
  {
    AfamWriter w(path, h);
    for (size_t i = 0; i + 1 < m.entries.size(); ++i) w.add(m.entries[i], m.payloads[i].data());
    EXPECT_EQ(countTempFiles(dir, "out.afam.tmp-"), 1u);
  }
  EXPECT_EQ(countTempFiles(dir, "out.afam"), 0u) << "neither the file nor its temporary remains";
  // An existing file is only replaced on commit.
  writeFile("atomic/out.afam", h, m);
  const auto before = readAll(path);
  {
    AfamWriter w(path, smallHeader(EncodingMode::Fixed));
    w.add(m.entries[0], m.payloads[0].data());
  }
  EXPECT_EQ(readAll(path), before);
  EXPECT_EQ(countTempFiles(dir, "out.afam.tmp-"), 0u);
}

TEST(AfamFile, OpenErrors) {
  EXPECT_THROW(AfamFile::open(tempDir() + "/does_not_exist.afam"), IoError);
  const std::string empty = tempDir() + "/empty.afam";
  writeAll(empty, {});
  EXPECT_THROW(AfamFile::open(empty), FormatError);
}

class CorruptFile : public testing::Test {
 protected:
  void SetUp() override {
    header_ = smallHeader();
    models_ = makeModels(header_);
    path_ = writeFile("good.afam", header_, models_);
    size_ = readAll(path_).size();
  }
  VolumeHeader header_;
  Models models_;
  std::string path_;
  size_t size_ = 0;
};

TEST_F(CorruptFile, TruncationAtManyOffsets) {
  std::vector<size_t> cuts = {0,    1,    7,    8,         100,        1019,      1023,     1024,
                              1025, 1064, 2000, size_ / 2, size_ - 64, size_ - 4, size_ - 1};
  for (size_t c = 1024; c < size_; c += 997) cuts.push_back(c);
  for (size_t cut : cuts) {
    if (cut >= size_) continue;
    SCOPED_TRACE(cut);
    const std::string what = expectFormatError(path_, [&](std::vector<char>& b) { b.resize(cut); });
    if (cut >= 8) {
      EXPECT_NE(what.find("truncated"), std::string::npos) << what;
    }
  }
}

TEST_F(CorruptFile, BadMagic) {
  const std::string w = expectFormatError(path_, [](std::vector<char>& b) { b[0] = 'X'; });
  EXPECT_NE(w.find("magic"), std::string::npos) << w;
  const std::string notAfam = tempDir() + "/text.afam";
  writeAll(notAfam, std::vector<char>(5000, 'a'));
  try {
    AfamFile::open(notAfam);
    ADD_FAILURE();
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("magic"), std::string::npos);
  }
}

TEST_F(CorruptFile, UnknownVersion) {
  const std::string w = expectFormatError(path_, [](std::vector<char>& b) {
    const uint32_t v = 4;
    std::memcpy(&b[8], &v, 4);
  });
  EXPECT_NE(w.find("version 4"), std::string::npos) << w;
}

TEST_F(CorruptFile, HeaderChecksum) {
  for (size_t off : {24, 100, 180, 300, 1000}) {
    const std::string w = expectFormatError(path_, [&](std::vector<char>& b) { b[off] ^= 0x10; });
    EXPECT_NE(w.find("header checksum"), std::string::npos) << w;
  }
}

TEST_F(CorruptFile, IndexChecksum) {
  for (size_t off : {1024 + 3, 1024 + 40, 1024 + 40 * 5 + 30}) {
    const std::string w = expectFormatError(path_, [&](std::vector<char>& b) { b[off] ^= 0x01; });
    EXPECT_NE(w.find("index checksum"), std::string::npos) << w;
  }
}

TEST_F(CorruptFile, PayloadChecksumNamesTheBlock) {
  auto f = AfamFile::open(path_);
  const ModelEntry e = f->entries()[7];
  const std::string w =
      expectFormatError(path_, [&](std::vector<char>& b) { b[e.offset + 5] ^= 0x40; });
  EXPECT_NE(w.find("payload checksum"), std::string::npos) << w;
  EXPECT_NE(w.find(Partition::blockName(e.level, e.block)), std::string::npos) << w;
}

// Rewrites header fields (and the header checksum, so the field check itself is reached).
namespace {
void patchHeader(std::vector<char>& b, size_t off, const void* v, size_t n) {
  std::memcpy(&b[off], v, n);
  const uint32_t crc = crc32(b.data(), 1020);
  std::memcpy(&b[1020], &crc, 4);
}
}  // namespace

TEST_F(CorruptFile, AbsurdCountsAndSizes) {
  const int64_t hugeDim = int64_t(1) << 40;
  expectFormatError(path_, [&](std::vector<char>& b) { patchHeader(b, 24, &hugeDim, 8); });
  const int32_t levels = 1000;
  expectFormatError(path_, [&](std::vector<char>& b) { patchHeader(b, 120, &levels, 4); });
  const int32_t blocks = 1 << 30;
  expectFormatError(path_, [&](std::vector<char>& b) { patchHeader(b, 124, &blocks, 4); });
  const uint64_t count = uint64_t(1) << 60;
  const std::string w =
      expectFormatError(path_, [&](std::vector<char>& b) { patchHeader(b, 144, &count, 8); });
  EXPECT_NE(w.find("count"), std::string::npos) << w;
  // A consistent but enormous partition (65535 blocks per axis on 2^31 dims): rejected before
  // any allocation because the index cannot fit in the file.
  const int64_t big = int64_t(1) << 30;
  const int32_t bigBlocks = 65535;
  expectFormatError(path_, [&](std::vector<char>& b) {
    for (int a = 0; a < 3; ++a) std::memcpy(&b[24 + 8 * a], &big, 8);
    patchHeader(b, 124, &bigBlocks, 4);
  });
  const uint8_t mode = 9;
  expectFormatError(path_, [&](std::vector<char>& b) { patchHeader(b, 136, &mode, 1); });
  const int32_t degree = 0;
  expectFormatError(path_, [&](std::vector<char>& b) { patchHeader(b, 128, &degree, 4); });
  const uint32_t entrySize = 80;
  expectFormatError(path_, [&](std::vector<char>& b) { patchHeader(b, 20, &entrySize, 4); });
  const uint64_t fileSize = uint64_t(size_) + 4096;
  expectFormatError(path_, [&](std::vector<char>& b) { patchHeader(b, 168, &fileSize, 8); });
  const uint32_t tag = 0x04030201;
  const std::string e =
      expectFormatError(path_, [&](std::vector<char>& b) { patchHeader(b, 12, &tag, 4); });
  EXPECT_NE(e.find("byte order"), std::string::npos);
}

TEST_F(CorruptFile, OffsetsPastTheEnd) {
  const uint64_t past = uint64_t(size_) + 64;
  const std::string w = expectFormatError(
      path_, [&](std::vector<char>& b) { afam_test::patchIndex(b, 3, 0, &past, 8); });
  EXPECT_NE(w.find("outside"), std::string::npos) << w;
  const uint64_t wrap = ~uint64_t(0) - 63;
  expectFormatError(path_, [&](std::vector<char>& b) { afam_test::patchIndex(b, 3, 0, &wrap, 8); });
  uint64_t payloadOffset;
  std::memcpy(&payloadOffset, &readAll(path_)[160], 8);
  const uint64_t misaligned = payloadOffset + 2;
  expectFormatError(path_,
                    [&](std::vector<char>& b) { afam_test::patchIndex(b, 0, 0, &misaligned, 8); });
  const uint64_t before = payloadOffset - 64;  // inside the index
  expectFormatError(path_,
                    [&](std::vector<char>& b) { afam_test::patchIndex(b, 0, 0, &before, 8); });
  const uint16_t hugeNcp[3] = {65535, 65535, 65535};
  const std::string n = expectFormatError(
      path_, [&](std::vector<char>& b) { afam_test::patchIndex(b, 2, 8, hugeNcp, 6); });
  EXPECT_NE(n.find("NCP 65535"), std::string::npos) << n;
  const uint16_t zeroNcp[3] = {0, 1, 1};
  expectFormatError(path_,
                    [&](std::vector<char>& b) { afam_test::patchIndex(b, 2, 8, zeroNcp, 6); });
  for (const uint16_t flags :
       {uint16_t(0x200), uint16_t(3), uint16_t(0x102)}) {  // unknown bit, kind, coded constant
    const std::string f = expectFormatError(
        path_, [&](std::vector<char>& b) { afam_test::patchIndex(b, 2, 14, &flags, 2); });
    EXPECT_NE(f.find("index entry 2"), std::string::npos) << f;
  }
  const uint32_t alignment = 3;
  expectFormatError(path_, [&](std::vector<char>& b) { patchHeader(b, 440, &alignment, 4); });
  const uint64_t total = 12345;
  expectFormatError(path_, [&](std::vector<char>& b) { patchHeader(b, 432, &total, 8); });
}

TEST_F(CorruptFile, RandomByteFlipsNeverCrash) {
  // A flipped bit anywhere is a FormatError, except in the alignment padding between payloads,
  // which no checksum covers: there the file must still read back exactly.
  std::mt19937 rng(42);
  const auto good = readAll(path_);
  int detected = 0;
  for (int t = 0; t < 300; ++t) {
    auto bytes = good;
    const size_t off = rng() % size_;
    bytes[off] ^= char(1 << (rng() % 8));
    const std::string bad = path_ + ".flip";
    writeAll(bad, bytes);
    try {
      auto f = AfamFile::open(bad);
      for (size_t i = 0; i < f->entries().size(); ++i)
        ASSERT_EQ(f->readPayload(int64_t(i)), models_.payloads[i])
            << "undetected change at byte " << off;
    } catch (const FormatError&) {
      ++detected;
    }
  }
  EXPECT_GT(detected, 200);
}

TEST(AfamFile, ConcurrentReads) {
  const VolumeHeader h = smallHeader();
  const Models m = makeModels(h);
  const std::string path = writeFile("threads.afam", h, m);
  auto f = AfamFile::open(path);
  std::vector<std::thread> threads;
  std::atomic<int> bad{0};
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      for (int rep = 0; rep < 20; ++rep)
        for (size_t i = size_t(t); i < m.entries.size(); i += 4)
          if (f->readPayload(int64_t(i)) != m.payloads[i]) ++bad;
    });
  for (auto& th : threads) th.join();
  EXPECT_EQ(bad.load(), 0);
}
