// SPDX-License-Identifier: BSD-3-Clause
// Micro-block samples from a streaming volume source: the Partition's sampling rule applied to
// whole z-planes, of which only the ones a row of blocks needs are read.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "afam/base/huge_pages.hpp"
#include "afam/format/partition.hpp"
#include "afam/sampling/level_filter.hpp"
#include "afam/volume/volume_source.hpp"

namespace afam {

/// Runs fn(block) for block in [0, count), on several threads when the caller provides them
/// (the encoder's sampling pool), else in order on the calling thread.
using BlockLoop = std::function<void(int64_t count, const std::function<void(int64_t)>& fn)>;

/// Planes read by PlaneReader: their samples as floats, or as the source stores them
/// (VolumeSource::storedType: 1- and 2-byte integers, each sample's float its plain conversion).
struct PlaneChunk {
  const void* samples = nullptr;
  SampleType type = SampleType::Float32;
};

/// Reads rows of listed z-planes of a source into a buffer: consecutive planes in one read call,
/// or, given a loop and a source that allows concurrentReads, in pieces of a few megabytes read
/// in parallel (the same samples).
class PlaneReader {
 public:
  PlaneReader(VolumeSource& src, Index3 dims);
  /// Rows [y0, y0 + yCount) of planes zs (ascending, distinct), plane i at the result's samples
  /// + i * dims[0] * yCount samples, valid until the next read; as the source stores them where
  /// it can say so (storedType), else floats. The reader's buffer only grows: it is not
  /// allocated, page-faulted or cleared again.
  PlaneChunk read(const std::vector<int64_t>& zs, int64_t y0, int64_t yCount,
                  const BlockLoop& loop = {});
  uint64_t bytesRead() const { return bytesRead_; }
  /// The buffer's size: the largest chunk read so far.
  size_t bufferBytes() const { return buf_.size() * sizeof(float); }

 private:
  VolumeSource& src_;
  int64_t rowSize_;
  uint64_t bytesRead_ = 0;
  HugePageVector<float> buf_;
};

/// How many planes sampleBlockRow reads at once: up to 256 MB (the fewest reads: a process that
/// holds batches of rows anyway), or at most a quarter of the samples they fill too (a rank of a
/// team, whose memory beside its piece is one line of blocks).
enum class ChunkBudget { Large, QuarterOfSamples };

/// Fills the samples of every block in `blocks` (all in the same z-row of one level): the rows of
/// the z-planes the blocks need are read in chunks (one readRows per run of consecutive planes;
/// whole planes for a whole row of blocks) as large as `budget` allows, at least the planes of one
/// z-sample (the samples do not depend on the chunks), and each block is filtered from a chunk
/// separably (y, then x, then z; sums in double), blocks in parallel through `loop` when given.
/// out[b] is resized to the block's (ghosted) sample count. Missing samples (NaN) stay NaN at
/// grid samples; a filtered sample with a missing one among its taps is the weighted mean of the
/// valid ones where they hold more than half of the filter's weight, else missing (NaN). `ghost`
/// adds one sample on each side at the same spacing (DS payload layout); `sampling` says how coarse
/// levels are filtered (see LevelSampling).
void sampleBlockRow(const Partition& part, PlaneReader& planes, int level,
                    const std::vector<Int3>& blocks, bool ghost, LevelSampling sampling,
                    std::vector<std::vector<float>*>& out, const BlockLoop& loop = {},
                    ChunkBudget budget = ChunkBudget::Large);

/// The taps sampleBlockRow filters the blocks of one z-row of a level with, flattened for
/// filteredSample (level_filter.hpp): each axis' taps are its entries of `first` (samples + 1 of
/// them, from `at`), which say where its samples' taps lie in index and weight.
struct RowTaps {
  struct Block {
    uint64_t x = 0, y = 0;  ///< where the block's x and y taps start in `first`
    int nx = 0, ny = 0;     ///< its samples along x and y (ghosts included)
  };
  std::vector<int64_t> index;
  std::vector<double> weight;
  std::vector<uint64_t> first;
  std::vector<Block> blocks;  ///< in the order of the blocks asked for
  uint64_t z = 0;             ///< where the row's z taps (one for every block) start in `first`
  int nz = 0;                 ///< the row's samples along z
  AxisTapsView view(uint64_t at) const { return {index.data(), weight.data(), first.data() + at}; }
  /// Samples of block b (nx * ny * nz).
  size_t samples(size_t b) const {
    return size_t(blocks[b].nx) * size_t(blocks[b].ny) * size_t(nz);
  }
};

/// sampleBlockRow's taps of `blocks` (all in one z-row of the level).
RowTaps rowTaps(const Partition& part, int level, const std::vector<Int3>& blocks, bool ghost,
                LevelSampling sampling);

/// Extracts micro-block samples of (level, ijk) from a full in-memory volume (x fastest), with the
/// Partition's sampling rule (linear interpolation at fractional positions). ghost adds one sample
/// on each side at the same spacing, clamped to the volume (DS payload layout).
std::vector<float> extractBlock(const Partition& part, const float* volume, int level, Int3 ijk,
                                bool ghost = false, LevelSampling sampling = LevelSampling::Point);

/// Streams the micro-block samples of one z-row of blocks of a level from a source, reading only
/// the planes needed (in chunks, see sampleBlockRow). Used by the encoder, `afam verify --against`
/// and tests.
class BlockRowReader {
 public:
  BlockRowReader(VolumeSource& source, const Partition& partition);
  ~BlockRowReader();
  /// out[j * bx + i] = samples of block (i, j, kz), x fastest; ghost as in extractBlock.
  void readRow(int level, int kz, bool ghost, LevelSampling sampling,
               std::vector<std::vector<float>>& out);
  uint64_t bytesRead() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace afam
