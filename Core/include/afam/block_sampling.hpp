// SPDX-License-Identifier: BSD-3-Clause
// Micro-block samples from a streaming volume source: the Partition's sampling rule applied to
// whole z-planes, of which only the ones a row of blocks needs are read.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "afam/partition.hpp"
#include "afam/volume_source.hpp"

namespace afam {

/// Keeps the most recently used z-planes of a source (two slots).
class PlaneCache {
 public:
  PlaneCache(VolumeSource& src, Index3 dims);
  const float* get(int64_t z);
  uint64_t bytesRead() const { return bytesRead_; }

 private:
  struct Slot {
    int64_t z = -1;
    uint64_t used = 0;
    std::vector<float> data;
  };
  VolumeSource& src_;
  size_t plane_;
  Slot slot_[2];
  uint64_t tick_ = 0, bytesRead_ = 0;
};

/// Fills the samples of every block in `blocks` (all in the same z-row of one level) by walking
/// the z-samples in order; out[b] is resized to the block's (ghosted) sample count.
/// `ghost` adds one sample on each side at the same spacing (DS payload layout); `sampling` says how
/// coarse levels are filtered (see LevelSampling).
void sampleBlockRow(const Partition& part, PlaneCache& planes, int level, const std::vector<Int3>& blocks,
                    bool ghost, LevelSampling sampling, std::vector<std::vector<float>*>& out);

/// Extracts micro-block samples of (level, ijk) from a full in-memory volume (x fastest), with the
/// Partition's sampling rule (linear interpolation at fractional positions). ghost adds one sample
/// on each side at the same spacing, clamped to the volume (DS payload layout).
std::vector<float> extractBlock(const Partition& part, const float* volume, int level, Int3 ijk,
                                bool ghost = false, LevelSampling sampling = LevelSampling::Point);

/// Streams the micro-block samples of one z-row of blocks of a level from a source, reading only
/// the planes needed (two cached). Used by the encoder, `afam verify --against` and tests.
class BlockRowReader {
 public:
  BlockRowReader(VolumeSource& source, const Partition& partition);
  ~BlockRowReader();
  /// out[j * bx + i] = samples of block (i, j, kz), x fastest; ghost as in extractBlock.
  void readRow(int level, int kz, bool ghost, LevelSampling sampling, std::vector<std::vector<float>>& out);
  uint64_t bytesRead() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace afam
