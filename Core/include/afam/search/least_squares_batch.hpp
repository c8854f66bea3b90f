// SPDX-License-Identifier: BSD-3-Clause
// Least-squares residuals of many blocks at once: what the NCP search asks of a fit, answered ahead
// of it for a whole batch of blocks (on the GPU: afam/cuda/encode/make_gpu_least_squares.hpp; on
// the CPU: CpuLeastSquaresBatch, the reference, of the same math).
//
// Math. On each axis the least-squares fit projects the samples onto the span of the collocation
// matrix A (n x ncp); with A = QR (Q orthonormal, n x ncp) the projection is Q Q^T, and the tensor
// fit's projection is the Kronecker product of the axes' (separable least squares). Its residual
// sum of squares is |s - m|^2 - |(Qz^T (x) Qy^T (x) Qx^T)(s - m)|^2, where m is the block's mean
// (B-splines reproduce constants, so removing it changes no residual and keeps the difference of
// two large sums away from where double precision runs out). The rows of Q^T per axis come from
// axisProjection; the contractions are x, then y, then z.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "afam/base/types.hpp"
#include "afam/format/partition.hpp"

namespace afam {

/// One question: block `block` of the batch (setBlocks) fitted with ncp control points per axis.
struct LsqRequest {
  int32_t block = 0;
  Int3 ncp{};
};

/// The answer: the block's sum of squared deviations from its mean, and the least-squares fit's
/// residual sum of squares (both double).
struct LsqResidual {
  double squares = 0, residual = 0;
};

class LevelSampler;

/// Where a batch's blocks are boxes of a volume's own samples (the finest level's, a copy of the
/// volume held by a LevelSampler): each block's first sample in the volume.
struct VolumeBoxes {
  const LevelSampler* copy = nullptr;
  std::vector<Index3> origins;
};

/// Batched least-squares residuals (see the file's comment). Not thread-safe: one caller.
class LeastSquaresBatch {
 public:
  virtual ~LeastSquaresBatch() = default;
  /// The blocks of the batch the requests refer to: samples x fastest (n[0]*n[1]*n[2] finite
  /// floats each), valid until the next setBlocks; degree 1..5 (reduced per axis as the fit does).
  virtual void setBlocks(const std::vector<const float*>& samples, const std::vector<Int3>& n,
                         int degree) = 0;
  /// setBlocks for blocks whose samples are also boxes of the volume copy `boxes.copy` holds: a
  /// batch that reads that copy where it lies (a GPU's, on its own device) takes them from there,
  /// the same floats, instead of handing `samples` over; the others call setBlocks.
  virtual void setBlocksIn(const VolumeBoxes& boxes, const std::vector<const float*>& samples,
                           const std::vector<Int3>& n, int degree) {
    (void)boxes;
    setBlocks(samples, n, degree);
  }
  /// The residual of each request, in order. Throws (GpuError on the GPU) when the device fails.
  virtual void residuals(const std::vector<LsqRequest>& requests,
                         std::vector<LsqResidual>& out) = 0;
  /// What computes them, in words ("cpu", or the GPU's name).
  virtual std::string description() const = 0;
  /// How many requests one call answers in about the time of one (a GPU's multiprocessors, each
  /// taking a request): askAhead asks up to that many a round, ahead of the searches' next
  /// questions. 1: one at a time (the CPU reference).
  virtual int64_t requestsAtOnce() const { return 1; }
};

/// The rows of Q^T (ncp x n, row-major, double) for one axis of n samples fitted with ncp control
/// points (degree reduced by effectiveDegree): Q the orthonormal factor of the collocation matrix.
/// Throws InvalidArgument as collocationMatrix does.
std::vector<double> axisProjection(int n, int ncp, int degree);

/// axisProjection for many (n, ncp, degree), each computed once, laid out one after another in
/// one array (for a device upload): offsetOf gives where a matrix starts.
class AxisProjections {
 public:
  /// Where the matrix of (n, ncp, degree) starts in values(), computing it the first time.
  uint64_t offsetOf(int n, int ncp, int degree);
  const std::vector<double>& values() const { return values_; }

 private:
  std::map<std::tuple<int, int, int>, uint64_t> offsets_;
  std::vector<double> values_;
};

/// The reference on the CPU, one thread, in the order of the file's comment.
class CpuLeastSquaresBatch final : public LeastSquaresBatch {
 public:
  void setBlocks(const std::vector<const float*>& samples, const std::vector<Int3>& n,
                 int degree) override;
  /// From a CpuLevelSampler's copy, the boxes gathered into the batch's own buffer (the GPU's
  /// gather, on the CPU); from any other, setBlocks.
  void setBlocksIn(const VolumeBoxes& boxes, const std::vector<const float*>& samples,
                   const std::vector<Int3>& n, int degree) override;
  void residuals(const std::vector<LsqRequest>& requests, std::vector<LsqResidual>& out) override;
  std::string description() const override { return "cpu"; }

 private:
  std::vector<std::vector<float>> gathered_;  ///< setBlocksIn's boxes
  std::vector<const float*> samples_;
  std::vector<Int3> n_;
  int degree_ = 2;
  AxisProjections projections_;
  std::vector<double> centred_, afterX_, afterY_;
};

}  // namespace afam
