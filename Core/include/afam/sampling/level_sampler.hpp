// SPDX-License-Identifier: BSD-3-Clause
// The coarse levels' block samples filtered from a copy of the whole volume held beside the
// encoder: on the GPU (afam/cuda/encode/make_gpu_level_sampler.hpp), or CpuLevelSampler, the
// reference, of the same math (level_filter.hpp). The encoder loads the copy while it scans the
// volume's range (the one read of the volume that every encode makes), then asks it for the z-rows
// of blocks of the levels filtered through a box (LevelSampling::Box, coarser than the volume)
// instead of reading the volume again for each such level and filtering it on the CPU.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "afam/sampling/block_sampling.hpp"
#include "afam/volume/sample_type.hpp"

namespace afam {

/// See the file's comment. One encode at a time; load() may be called from several threads.
class LevelSampler {
 public:
  virtual ~LevelSampler() = default;
  /// Makes room for a volume of `dims` samples stored as `type` (1- or 2-byte integers, or
  /// float32); false, with the reason in `why`, where it cannot hold it (then it is not used).
  virtual bool reserve(Index3 dims, SampleType type, std::string& why) = 0;
  /// Planes [z0, z0 + nz) as stored (x fastest), after reserve. Thread-safe for distinct planes.
  virtual void load(int64_t z0, int64_t nz, const void* samples) = 0;
  /// sampleBlockRow's samples of `blocks` (one z-row of `level`), the same floats bit for bit,
  /// once every plane is loaded; out[b] is resized to block b's samples. `loop` may share the work
  /// of handing them out.
  virtual void sampleRow(const Partition& part, int level, const std::vector<Int3>& blocks,
                         bool ghost, LevelSampling sampling, std::vector<std::vector<float>*>& out,
                         const BlockLoop& loop = {}) = 0;
  /// Frees the volume's copy.
  virtual void release() = 0;
  /// What filters ("cpu", or the GPU's name).
  virtual std::string description() const = 0;
};

/// The reference: the copy in host memory, each sample filteredSample's.
class CpuLevelSampler final : public LevelSampler {
 public:
  bool reserve(Index3 dims, SampleType type, std::string& why) override;
  void load(int64_t z0, int64_t nz, const void* samples) override;
  void sampleRow(const Partition& part, int level, const std::vector<Int3>& blocks, bool ghost,
                 LevelSampling sampling, std::vector<std::vector<float>*>& out,
                 const BlockLoop& loop = {}) override;
  void release() override;
  std::string description() const override { return "cpu"; }
  /// The box of n samples from `origin` of the copy, as floats (boxSample), into out.
  void box(const Index3& origin, const Int3& n, float* out) const;

 private:
  Index3 dims_{};
  SampleType type_ = SampleType::Float32;
  std::vector<unsigned char> volume_;
};

/// Whether `type` is one a LevelSampler holds.
bool levelSamplerHolds(SampleType type);

}  // namespace afam
