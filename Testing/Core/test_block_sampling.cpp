// SPDX-License-Identifier: BSD-3-Clause
// Block sampling from a streaming source: with ChunkBudget::QuarterOfSamples a row of blocks is
// read in chunks of planes bounded by the samples it fills (what an encoding rank holds beside its
// piece), and the chunking does not change a sample (each block alone is sampled in other chunks).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

#include "afam/sampling/block_sampling.hpp"
#include "afam/volume/marschner_lobb.hpp"

using namespace afam;

namespace {

/// A source that records the largest read (in floats) and the number of reads (not thread-safe:
/// no concurrentReads).
class CountingSource : public ArraySource {
 public:
  using ArraySource::ArraySource;
  bool concurrentReads() const override { return concurrent; }
  void readRows(int64_t z0, int64_t nz, int64_t y0, int64_t ny, float* out) override {
    largest = std::max(largest, size_t(nz * ny * dims()[0]));
    ++reads;
    ArraySource::readRows(z0, nz, y0, ny, out);
  }
  size_t largest = 0;
  int reads = 0;
  bool concurrent = false;
};

struct RowCase {
  LevelSampling sampling;
  bool ghost;
};

}  // namespace

TEST(BlockSampling, QuarterBudgetChunksHoldAQuarterOfTheRowOrOneSamplesPlanes) {
  const Index3 dims{96, 80, 88};
  std::vector<float> v(size_t(dims[0] * dims[1] * dims[2]));
  marschnerLobbSlab(MarschnerLobb{}, dims, 0, dims[2], v.data());
  const Partition part(dims, 4, 8);
  for (const RowCase rc : {RowCase{LevelSampling::Point, false}, RowCase{LevelSampling::Box, false},
                           RowCase{LevelSampling::Box, true}}) {
    for (int l = 0; l < part.levels(); ++l) {
      const Int3 nb = part.blocksPerAxis(l);
      for (int kz = 0; kz < nb[2]; ++kz) {
        SCOPED_TRACE(testing::Message()
                     << "level " << l << " z-row " << kz << " box "
                     << (rc.sampling == LevelSampling::Box) << " ghost " << rc.ghost);
        CountingSource src(v.data(), dims);
        PlaneReader planes(src, dims);
        std::vector<Int3> row;
        for (int j = 0; j < nb[1]; ++j)
          for (int i = 0; i < nb[0]; ++i) row.push_back({i, j, kz});
        std::vector<std::vector<float>> samples(row.size());
        std::vector<std::vector<float>*> outs;
        size_t rowFloats = 0;
        for (auto& s : samples) outs.push_back(&s);
        sampleBlockRow(part, planes, l, row, rc.ghost, rc.sampling, outs, {},
                       ChunkBudget::QuarterOfSamples);
        for (const auto& s : samples) rowFloats += s.size();
        // One z-sample's planes: a box of width stride + the ghost's step, whole rows of the
        // volume.
        const size_t oneSample = size_t(part.stride(l) + 2) * size_t(dims[0] * dims[1]);
        EXPECT_LE(src.largest, std::max(rowFloats / 4, oneSample));
        EXPECT_EQ(planes.bufferBytes() % (sizeof(float) * size_t(dims[0])), 0u);
        EXPECT_LE(planes.bufferBytes(), sizeof(float) * std::max(rowFloats / 4, oneSample));
        // The same samples as each block sampled alone (other chunks) from the whole volume.
        for (size_t b = 0; b < row.size(); ++b) {
          ASSERT_EQ(samples[b], extractBlock(part, v.data(), l, row[b], rc.ghost, rc.sampling))
              << "block " << b;
        }
        if (l == part.levels() - 1 && !rc.ghost) {
          EXPECT_GT(src.reads, 1) << "a finest row is read in several chunks";
        }
      }
    }
  }
}

namespace {

/// A wrapper that counts its reads and the threads they ran on (thread-safe, as a concurrent
/// source must be).
class ThreadCountingSource : public WrappingSource {
 public:
  using WrappingSource::WrappingSource;
  void readSlab(int64_t z0, int64_t nz, float* out) override {
    readRows(z0, nz, 0, dims()[1], out);
  }
  void readRows(int64_t z0, int64_t nz, int64_t y0, int64_t ny, float* out) override {
    {
      std::lock_guard<std::mutex> lock(m_);
      ++reads;
      threads.insert(std::this_thread::get_id());
    }
    inner_.readRows(z0, nz, y0, ny, out);
  }
  std::mutex m_;
  int reads = 0;
  std::set<std::thread::id> threads;
};

/// The same, passing on the inner source's samples as stored.
class StoredCountingSource : public ThreadCountingSource {
 public:
  using ThreadCountingSource::ThreadCountingSource;
  std::optional<SampleType> storedType() const override { return inner_.storedType(); }
  void readStoredRows(int64_t z0, int64_t nz, int64_t y0, int64_t ny, void* out) override {
    {
      std::lock_guard<std::mutex> lock(m_);
      ++reads;
      threads.insert(std::this_thread::get_id());
    }
    inner_.readStoredRows(z0, nz, y0, ny, out);
  }
};

/// A loop on `n` threads of its own (as the encoder's sampling pool runs fn).
/// A loop over n threads, piece i on thread i mod n: every thread reads a piece where there are n
/// or more (threads taking pieces as they come may leave one thread all of them on a loaded
/// machine: the sanitizer build under ctest -j2 did).
BlockLoop threadsLoop(int n) {
  return [n](int64_t count, const std::function<void(int64_t)>& fn) {
    std::vector<std::thread> pool;
    for (int t = 0; t < n; ++t)
      pool.emplace_back([&fn, count, n, t] {
        for (int64_t i = t; i < count; i += n) fn(i);
      });
    for (std::thread& t : pool) t.join();
  };
}

}  // namespace

// A raw file read through a loop: in pieces on several threads, the same samples as read in one
// call a run of planes, as stored (int16) where the source gives them so, else floats; a source
// without concurrentReads is read on the calling thread as before.
TEST(BlockSampling, PlanesAreReadInParallelPiecesAsTheSameSamples) {
  const Index3 dims{700, 400, 40};
  std::vector<int16_t> raw(size_t(dims[0] * dims[1] * dims[2]));
  for (size_t i = 0; i < raw.size(); ++i) raw[i] = int16_t((i * 2654435761u) >> 17);
  const std::string path = ::testing::TempDir() + "planes_700x400x40_int16.raw";
  {
    std::ofstream f(path, std::ios::binary);
    f.write(reinterpret_cast<const char*>(raw.data()), std::streamsize(raw.size() * 2));
  }
  RawFileSource file(path, dims, SampleType::Int16);
  ASSERT_TRUE(file.concurrentReads());
  ASSERT_EQ(file.storedType(), SampleType::Int16);
  std::vector<int64_t> zs{2};  // runs of 1, 17 and 12 planes
  for (int64_t z = 5; z < 22; ++z) zs.push_back(z);
  for (int64_t z = 28; z < 40; ++z) zs.push_back(z);
  const size_t plane = size_t(dims[0]) * 300;  // rows 50..349: 4 planes a piece of 2^20 samples
  PlaneReader serial(file, dims);
  const PlaneChunk a = serial.read(zs, 50, 300);
  ASSERT_EQ(a.type, SampleType::Int16);
  const auto* as = static_cast<const int16_t*>(a.samples);
  const std::vector<int16_t> expected(as, as + zs.size() * plane);
  size_t wrong = 0;
  for (size_t i = 0; i < zs.size(); ++i)
    for (size_t k = 0; k < plane; ++k)
      wrong += expected[i * plane + k] != raw[size_t(zs[i] * dims[1] + 50) * size_t(dims[0]) + k];
  EXPECT_EQ(wrong, 0u);
  EXPECT_EQ(serial.bytesRead(), zs.size() * plane * 2);

  StoredCountingSource stored(file);
  PlaneReader parallelStored(stored, dims);
  const PlaneChunk b = parallelStored.read(zs, 50, 300, threadsLoop(4));
  ASSERT_EQ(b.type, SampleType::Int16);
  EXPECT_TRUE(std::equal(expected.begin(), expected.end(), static_cast<const int16_t*>(b.samples)));
  EXPECT_EQ(stored.reads, 1 + 5 + 3);  // the runs in pieces of at most 4 planes
  EXPECT_GE(stored.threads.size(), 2u);

  // A wrapper that does not say how its samples are stored: floats, in the same pieces.
  ThreadCountingSource counted(file);
  PlaneReader parallel(counted, dims);
  const PlaneChunk c = parallel.read(zs, 50, 300, threadsLoop(4));
  ASSERT_EQ(c.type, SampleType::Float32);
  const auto* cf = static_cast<const float*>(c.samples);
  EXPECT_TRUE(std::equal(expected.begin(), expected.end(), cf,
                         [](int16_t e, float f) { return float(e) == f; }));
  EXPECT_EQ(counted.reads, 1 + 5 + 3);
  EXPECT_GE(counted.threads.size(), 2u);
  EXPECT_EQ(parallel.bytesRead(), 2 * serial.bytesRead());  // floats, of 2-byte samples

  // Not concurrent (state of its own): one read a run, on the calling thread.
  std::vector<float> v(raw.begin(), raw.end());
  CountingSource plain(v.data(), dims);
  PlaneReader own(plain, dims);
  bool looped = false;
  const PlaneChunk d =
      own.read(zs, 50, 300, [&](int64_t count, const std::function<void(int64_t)>& fn) {
        looped = true;
        for (int64_t i = 0; i < count; ++i) fn(i);
      });
  EXPECT_FALSE(looped);
  EXPECT_EQ(plain.reads, 3);
  EXPECT_TRUE(std::equal(expected.begin(), expected.end(), static_cast<const float*>(d.samples),
                         [](int16_t e, float f) { return float(e) == f; }));
  std::remove(path.c_str());
}
