// SPDX-License-Identifier: BSD-3-Clause
// Separable tensor-product least-squares fitting of one micro-block, and its error on the samples.
//
// Method. Samples of an n0 x n1 x n2 block (x fastest) sit on uniform parameters u_k = k/(n-1)
// (u = 0 for a one-sample axis). On each axis the collocation matrix A (n x ncp, p+1 non-zeros per
// row, knots implied by afam::Knots) gives a banded normal matrix A^T A of half-bandwidth p. It is
// built and Cholesky-factored ONCE per (n, ncp, p) in double precision and cached in the fitter.
// The fit applies A^T along z (whole xy-planes as vectors), then y (x-rows as vectors), then x (the
// x-lines transposed, so that they are the vectors too), and then the banded solves, one axis at a
// time on the ncp0 x ncp1 x ncp2 coefficients. Because the tensor least-squares problem
// (Az (x) Ay (x) Ax) c = d has the normal matrix (Nz (x) Ny (x) Nx), this separable result equals
// the full tensor least-squares solution (tested against a dense solve).
//
// Stability. The implied knots are de Boor averages of uniform parameters, so NCP = n is a
// well-conditioned interpolation (collocation cond < 10 for p <= 3 at every n, see
// axisConditioning and test_stability.cpp), unlike plain uniform knots (cond ~ 1e9 for cubics at
// n = 128, where the normal equations break down).
//
// Magnitudes. No internal rescaling is done, by decision: every intermediate is double. Samples are
// finite floats (|x| <= 3.4e38), basis weights lie in [0, 1] and the normal matrices depend only on
// (n, ncp, p), so sums stay below ~1e44, far from double overflow; squares of errors stay below
// ~5e77. Float denormal samples are ordinary doubles. Only the final float32 control points can
// overflow (solution beyond FLT_MAX): that throws NumericError. Results at 1e30 and 1e-30 scale
// with the data (tested).
//
// Non-finite samples: the fit refuses them (NumericError naming the first offending sample's
// (x, y, z) and flat index); callers add the block's name. There is no masking policy.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/base/types.hpp"
#include "afam/spline/evaluate.hpp"
#include "afam/spline/interpolation_passes.hpp"
#include "afam/spline/rmse_range.hpp"

namespace afam {

/// Per-axis degree used for an axis of n samples: min(degree, n-1).
int effectiveDegree(int degree, int samples);

/// The interpolation system (NCP = n) of an axis of n samples at degree p (effectiveDegree), as
/// BlockFitter builds and factors it: what interpolation_passes.hpp needs to fit an interpolant
/// one line at a time (the GPU decoder's tables). Throws NumericError as a fit would.
InterpolationAxis interpolationAxis(int n, int p);

/// NCP clamped per axis to [p_axis+1, n_axis] for a scalar NCP request.
std::array<int, 3> clampNcp(int ncp, const std::array<int, 3>& samples,
                            const std::array<int, 3>& degrees);

/// Error of a model on the block's samples. min/max are of the model, evaluated on the samples.
struct ErrorStats {
  double rmse = 0, maxError = 0;
  double minValue = 0, maxValue = 0;
};

/// One fitted micro-model: per-axis NCP and effective degree, float32 control points x fastest.
struct FitResult {
  std::array<int, 3> ncp{}, degree{};
  std::vector<float> control;
  ErrorStats error;
  /// false: `error` was not measured on the samples (BlockFitter::fitWithin decided the bound
  /// without it; only error.rmse is set, to a bound on the RMSE: see there); measure() fills it.
  bool errorMeasured = true;

  /// Non-owning view for evaluateModel (valid while `control` is not reallocated).
  ModelView view() const {
    ModelView v;
    for (int a = 0; a < 3; ++a) v.knots[a] = Knots::make(ncp[a], degree[a]);
    v.control = control.data();
    return v;
  }
};

/// Reusable fitter; NOT thread-safe: one per thread. Caches per-axis factorisations keyed by
/// (n, ncp, p) and keeps its work buffers between calls, so a fit allocates nothing but its result.
class BlockFitter {
 public:
  BlockFitter();
  ~BlockFitter();
  BlockFitter(BlockFitter&&) noexcept;
  BlockFitter& operator=(BlockFitter&&) noexcept;
  BlockFitter(const BlockFitter&) = delete;
  BlockFitter& operator=(const BlockFitter&) = delete;

  /// Least-squares fit of samples (x fastest, n[0]*n[1]*n[2] floats) on uniform parameters
  /// k/(n-1). `degree` (1..5) is reduced per axis by effectiveDegree; ncp[a] must lie in
  /// [effectiveDegree(degree, n[a]) + 1, n[a]] (see clampNcp).
  /// Throws InvalidArgument for n < 1, a degree outside 1..5 or an NCP outside its range, and
  /// NumericError naming the sample if any sample is NaN or Inf (or if a control point overflows
  /// float32). With computeError the result's `error` holds the model's error on all samples.
  FitResult fit(const float* samples, std::array<int, 3> n, std::array<int, 3> ncp, int degree,
                bool computeError = true);

  /// Same as fit() but reuses `out`'s control-point storage (no allocation once it is large
  /// enough): the form for encoders fitting many blocks.
  void fitInto(const float* samples, std::array<int, 3> n, std::array<int, 3> ncp, int degree,
               bool computeError, FitResult& out);

  /// fitInto, then whether the model's RMSE on the samples is <= `bound`, the same answer as
  /// measuring it, mostly without measuring: the fit's exact least-squares residual
  /// (sumOfSquares - c^T A^T A c) bounds the model's RMSE from below and, with the float32 rounding
  /// of the control points, from above (rmseRange); only when the bound lies between the two is the
  /// error measured. Otherwise out.errorMeasured is false and out.error.rmse holds the decisive
  /// end of the range (> bound: false, <= bound: true); measure() then gives the full statistics.
  /// `sumOfSquares` is afam::sumOfSquares(samples, n): finite, it also vouches that the samples
  /// are (they are not scanned again). Throws as fitInto.
  bool fitWithin(const float* samples, std::array<int, 3> n, std::array<int, 3> ncp, int degree,
                 double bound, double sumOfSquares, FitResult& out);

  /// Whether `changed`, the model `fitted` (a least-squares fit of these samples, its error
  /// measured) with other control points (quantized, say), meets `bound`: the same answer as
  /// measuring it, mostly without measuring, from fitted's RMSE and the energy of the change
  /// (changedRmseRange). changed.errorMeasured and changed.error as in fitWithin. Throws
  /// InvalidArgument when the shapes differ or fitted's error was not measured.
  bool changeWithin(const float* samples, std::array<int, 3> n, const FitResult& fitted,
                    FitResult& changed, double bound);

  /// Measures the model's error on the samples unless model.errorMeasured.
  void measure(const float* samples, std::array<int, 3> n, FitResult& model);

  /// Error of an existing model against the samples, via separable evaluation on the sample grid
  /// (O(n^3 (p+1)), never point by point). Throws InvalidArgument if the model does not fit n.
  ErrorStats error(const float* samples, std::array<int, 3> n, const FitResult& model);

  /// Separable evaluation of the model on its n0 x n1 x n2 uniform sample grid (out resized).
  void evaluateOnGrid(const FitResult& model, std::array<int, 3> n, std::vector<float>& out);

  /// A block with missing samples (block_mask.hpp's words, bit set = valid; nullptr: none): until
  /// it is reset, error(), measure(), fitWithin() and changeWithin() judge models on the valid
  /// samples alone, always measuring (the least-squares ranges hold for all samples only), and
  /// min/max are the model's on them. Fits still use every sample: the caller fills the holes
  /// (hole_fill.hpp). The words must outlive their use.
  void setMask(const std::vector<uint32_t>* valid);

 private:
  /// The answer of fitWithin and changeWithin: the decisive end of the range (model unmeasured),
  /// else the measured error.
  bool decide(const RmseRange& range, double bound, const float* samples, std::array<int, 3> n,
              FitResult& model);

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Four doubles as one value (GCC/Clang vector extension): one AVX2 register where the caller is
/// compiled for AVX2, two SSE2 registers otherwise; each operation rounds as its scalar does.
using DoubleQuad = double __attribute__((vector_size(32)));

/// Error of model values (model(i) gives value i) against samples (count of them) on the samples
/// whose bit is set in `valid` (block_mask.hpp's words; nullptr: every sample); min/max are the
/// model's there. Without a mask the squares are summed in four lanes (value i in lane i mod 4,
/// the lanes added pairwise at the end), the lanes one DoubleQuad: four chains of additions
/// instead of one. Inlined always, so that a caller compiled for AVX2 (errorOnValid) runs the
/// lanes in one vector.
template <typename Model>
__attribute__((always_inline)) inline ErrorStats errorOnValidOf(const Model& model,
                                                                const float* samples, size_t count,
                                                                const uint32_t* valid) {
  ErrorStats es;
  es.minValue = std::numeric_limits<double>::infinity();
  es.maxValue = -es.minValue;
  double sum = 0;
  size_t used = 0;
  if (!valid) {
    const double inf = es.minValue;
    DoubleQuad lane = {0, 0, 0, 0}, most = {0, 0, 0, 0};
    DoubleQuad lo = {inf, inf, inf, inf}, hi = {-inf, -inf, -inf, -inf};
    size_t i = 0;
    for (; i + 4 <= count; i += 4) {
      const DoubleQuad m = {double(model(i)), double(model(i + 1)), double(model(i + 2)),
                            double(model(i + 3))};
      const DoubleQuad d = m - DoubleQuad{double(samples[i]), double(samples[i + 1]),
                                          double(samples[i + 2]), double(samples[i + 3])};
      lane += d * d;
      const DoubleQuad ad = d < 0 ? -d : d;  // |d|; -0 and NaN never exceed `most`
      most = ad > most ? ad : most;          // std::max(most, |d|)
      lo = m < lo ? m : lo;                  // std::min(lo, m)
      hi = m > hi ? m : hi;                  // std::max(hi, m)
    }
    for (; i < count; ++i) {  // value i in lane i mod 4
      const size_t l = i & 3;
      const double m = double(model(i)), d = m - double(samples[i]);
      lane[l] += d * d;
      most[l] = std::max(most[l], std::fabs(d));
      lo[l] = std::min(lo[l], m);
      hi[l] = std::max(hi[l], m);
    }
    sum = (lane[0] + lane[1]) + (lane[2] + lane[3]);
    for (size_t l = 0; l < 4; ++l) {
      es.maxError = std::max(es.maxError, most[l]);
      es.minValue = std::min(es.minValue, lo[l]);
      es.maxValue = std::max(es.maxValue, hi[l]);
    }
    es.rmse = std::sqrt(sum / double(std::max<size_t>(count, 1)));
    return es;
  }
  for (size_t i = 0; i < count; ++i) {
    if (valid && ((valid[i >> 5] >> (i & 31)) & 1u) == 0) continue;
    const double m = double(model(i)), d = m - double(samples[i]);
    sum += d * d;
    es.maxError = std::max(es.maxError, std::fabs(d));
    es.minValue = std::min(es.minValue, m);
    es.maxValue = std::max(es.maxValue, m);
    ++used;
  }
  es.rmse = std::sqrt(sum / double(std::max<size_t>(used, 1)));
  return es;
}

/// errorOnValidOf for model values in an array (compiled also for AVX2, chosen at run time: four
/// doubles a vector, no FMA, so the same sums).
ErrorStats errorOnValid(const float* model, const float* samples, size_t count,
                        const uint32_t* valid);

/// Sum of the squared samples of an n0 x n1 x n2 block, in double.
double sumOfSquares(const float* samples, std::array<int, 3> n);

/// The largest |v[i]| of `count` floats (0 for none; a NaN ignored, as std::max does).
float largestMagnitude(const float* v, size_t count);

/// The calling thread's fitter, kept for the thread's life: the encoder's fitting threads, the
/// decoding of interpolants (decodeInterpolant) and evaluateOnGrid share it, so that a thread
/// faults in one set of block-sized work buffers, not one per use (a small volume's encode was
/// a third page zeroing when each held its own). Whoever holds it across a call that may use it
/// again (setMask, the last solve's energy) keeps no state the other call changes: the decoding's
/// fits measure nothing.
BlockFitter& threadFitter();

/// Separable evaluation of the model on its n0 x n1 x n2 uniform sample grid (out resized), by
/// threadFitter().
void evaluateOnGrid(const FitResult& model, std::array<int, 3> n, std::vector<float>& out);

/// The n x ncp collocation matrix of one axis (row-major: entry (i, j) is control point j's basis
/// function at sample i's parameter i/(n-1)), the degree reduced by effectiveDegree. Throws
/// InvalidArgument for n < 1, a degree outside 1..5 or an NCP outside [p+1, n].
std::vector<double> collocationMatrix(int n, int ncp, int degree);

/// 2-norm condition number of the n x ncp collocation matrix on one axis (Eigen JacobiSVD), and of
/// the normal matrix A^T A (the square of the former, from the same singular values). The degree
/// is reduced by effectiveDegree; infinity when the matrix is rank deficient.
struct AxisConditioning {
  double collocation = 0, normal = 0;
};
AxisConditioning axisConditioning(int n, int ncp, int degree);

/// Peak signal-to-noise ratio in dB: 20 log10(valueRange / rmse); +inf when rmse == 0.
double psnr(double rmse, double valueRange);

}  // namespace afam
