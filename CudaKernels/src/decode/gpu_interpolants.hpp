// SPDX-License-Identifier: BSD-3-Clause
// The interpolant jobs of a GPU decoding batch (GpuDecodeKind::Interpolant): after the Lorenzo
// kernels have decoded a job's samples into its output (or, in the double interpolation form,
// parsed its residuals there, which a block a job then predicts level by level as the CPU codec
// does, value_prediction.hpp), the spline through them is fitted there,
// one line a thread in the fitter's order (interpolation_passes.hpp), in double scratch, and its
// points rounded to the job's step (rounded_points.hpp): the floats decodeInterpolant gives on the
// CPU, bit for bit. The axes' factored systems are built on the host (fit.hpp's
// interpolationAxis, kept per sample count and degree) and uploaded with the batch. Jobs run in
// groups whose scratch (two doubles a point) fits kGroupScratchBytes. Internal to GpuBlockDecoder.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "afam/cuda/decode/gpu_block_decoder.hpp"
#include "afam/spline/interpolation_passes.hpp"

namespace afam {

/// An axis system's arrays in the batch's axis area, as byte offsets from its start.
struct GpuAxisRef {
  uint32_t rowFirst = 0, rowLast = 0, columnOffset = 0;
  uint32_t columnWeight = 0, lower = 0, invDiag = 0;
  int32_t n = 0, p = 0;
};

/// One interpolant job: its index in the batch, its scratch (in doubles, from its group's start)
/// and its three axes (indices into the batch's GpuAxisRef table).
struct GpuInterpolantJob {
  uint64_t scratchOffset = 0;
  uint32_t job = 0;
  uint32_t axis[3] = {0, 0, 0};
};

class GpuInterpolants {
 public:
  /// Scratch of a group of jobs at most (one job larger than that runs alone, in its own size).
  static constexpr uint64_t kGroupScratchBytes = uint64_t(256) << 20;

  GpuInterpolants() = default;
  ~GpuInterpolants() { release(); }
  GpuInterpolants(const GpuInterpolants&) = delete;
  GpuInterpolants& operator=(const GpuInterpolants&) = delete;

  /// Lays out the interpolant jobs of `jobs` and queues the upload of their tables on `stream` (a
  /// cudaStream_t) through pinned staging, growing the device buffers; false when there are none.
  /// The batch before must have finished (its staging is reused). Throws GpuError when CUDA fails.
  bool upload(const std::vector<GpuDecodeJob>& jobs, void* stream);
  /// Queues the fits on `stream`, after the kernels that decode the samples: `jobs` (device) as
  /// uploaded by the decoder, `payloads` their stored bytes, `output` holding each job's samples
  /// (or, for samples in the double interpolation form, their residuals, predicted here first),
  /// `status` its words (a job whose word is set is skipped; one whose samples or points are beyond
  /// float32, or whose points do not round, sets it).
  void launch(const GpuDecodeJob* jobs, const uint8_t* payloads, float* output, uint32_t* status,
              void* stream);
  size_t scratchBytes() const { return scratchCapacity_; }
  void release() noexcept;

 private:
  /// A group of consecutive jobs of list_ that run together, and the most lines of any pass.
  struct Group {
    size_t first = 0, count = 0;
    int64_t lines = 0;
    uint64_t points = 0;  ///< the most points of a job
  };
  uint32_t axisIndex(int n, int p);

  std::map<std::pair<int, int>, InterpolationAxis> axes_;  // kept between batches
  std::vector<std::pair<int, int>> batchAxes_;             // the batch's, in GpuAxisRef order
  std::vector<GpuInterpolantJob> list_;
  std::vector<Group> groups_;
  uint64_t scratchNeeded_ = 0;  ///< doubles of the largest group
  // Device: the tables ([GpuAxisRef...][GpuInterpolantJob...][axis area]); the scratch.
  unsigned char* tables_ = nullptr;
  size_t tablesCapacity_ = 0;
  size_t jobsAt_ = 0, areaAt_ = 0;
  double* scratch_ = nullptr;
  size_t scratchCapacity_ = 0;
  unsigned char* staging_ = nullptr;  // pinned
  size_t stagingCapacity_ = 0;
};

}  // namespace afam
