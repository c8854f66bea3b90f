// SPDX-License-Identifier: BSD-3-Clause
// Where a GPU level sampler (gpu_level_sampler.cu) holds the volume's copy: for the GPU's
// least-squares batch (gpu_least_squares.cu) to take the finest level's blocks from it
// (LeastSquaresBatch::setBlocksIn) instead of having their samples handed over.
#pragma once

#include "afam/format/partition.hpp"
#include "afam/sampling/level_sampler.hpp"
#include "afam/volume/sample_type.hpp"

namespace afam {

/// A volume in device memory: samples of `type`, x fastest, on CUDA device `device`.
struct GpuVolumeCopy {
  const void* data = nullptr;  ///< null: none held
  Index3 dims{};
  SampleType type = SampleType::UInt8;
  int device = -1;
};

/// The copy `sampler` holds, where it is a GPU level sampler holding one (else data is null).
GpuVolumeCopy gpuVolumeCopy(const LevelSampler* sampler);

}  // namespace afam
