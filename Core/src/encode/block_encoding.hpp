// SPDX-License-Identifier: BSD-3-Clause
// One micro-block's model, chosen and stored by the encoder (private to Core): the fit with the
// bound check, and the compact representations (constant, coded spline, coded samples).
#pragma once

#include <cmath>
#include <cstdint>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "afam/encode/encoder.hpp"
#include "afam/format/block_codec.hpp"
#include "afam/spline/fit.hpp"

namespace afam {

/// Bounded modes promise each block's RMSE <= the bound on its own samples; Fixed does not.
inline bool bounded(EncodingMode mode) {
  return mode == EncodingMode::Adaptive || mode == EncodingMode::InLevel;
}

struct BlockTask {
  Int3 ijk{};
  bool search = false;
  std::vector<float> samples;
  /// A block with missing samples: the valid ones' mask words (block_mask.hpp), the holes of
  /// `samples` filled (hole_fill.hpp); empty when every sample is valid.
  std::vector<uint32_t> mask;
  ModelEntry entry;
  std::vector<uint8_t> stored;  ///< the payload as the file stores it (entry.storedSize bytes)
  int ncpStar = 0;
  int64_t fits = 0;
  bool complex = false;
  bool exact = false;          ///< stored as its samples (no NCP met the bound)
  bool reducedDegree = false;  ///< an axis has fewer samples than the degree needs
  /// Answers to its search's questions given ahead (EncoderOptions::leastSquares), at the bound
  /// searchBound gives; none: every question is a fit.
  NcpVerdicts verdicts;
  /// axisRoughness of `samples`, once computed (the noise probe's and the refinement's).
  std::optional<std::array<double, 3>> roughness;
  double rmse = 0,
         maxError = 0;  ///< of the stored model on the block's samples (the entry keeps floats)
  /// rmse and maxError were measured on the model a reader decodes from `stored`, as stored (an
  /// interpolant checked on the decoding of these very bytes): checkAsRead need not decode it.
  bool measuredAsRead = false;
};

/// The RMSE bound a searched block's fits must keep: kFitShare of the bound where the points are
/// then quantized (compact), the bound itself where they are stored as float32.
double searchBound(const EncoderOptions& opt, double bound);

struct FitContext {
  const EncoderOptions& opt;
  double bound;
  int level;
  std::string sourceName;
};

/// Compact storage: the NCP at which one fit tells whether a searched block is noise-dominated
/// (its spline would need nearly as many points as samples), where the block's content says the
/// probe could pay; none elsewhere.
/// `rough`: axisRoughness of t's samples.
std::optional<Int3> noiseProbeNcp(const FitContext& c, const BlockExtent& e, const BlockTask& t,
                                  const std::array<double, 3>& rough);

/// Whether a model whose error on the block's samples is `es` keeps the bound: their RMSE, or
/// every sample's error (a pointwise bound).
inline bool keeps(BoundKind kind, const ErrorStats& es, double bound) {
  return kind == BoundKind::MaxError ? es.maxError <= bound : es.rmse <= bound;
}

// Quantization steps of coded payloads, as factors of 2 sqrt(3) x the error budget (the step whose
// uniform rounding error alone would spend it), tried from the largest: a larger step is fewer
// bits, and a block whose error budget is not spent gains nothing from it.
constexpr double kStepFactors[] = {4.0, 3.2,  2.6, 2.1,  1.7, 1.4, 1.15,
                                   1.0, 0.85, 0.7, 0.55, 0.4, 0.3};
/// Where a ladder for an RMSE bound starts (largestPassingStepFrom's hint) when no other form of
/// the same values has answered: the samples' at factor 1, where uniform rounding alone spends the
/// budget (an RMSE of step / sqrt(12)), so their ladder ends there or next to it; a
/// spline's at factor 2.1, where 130 of the 203 coded splines of the corpus and the head MRI made
/// 301x370x316 (--detail 18) ended at RMSE 1e-2 (the basis averages the points' rounding; 64 more
/// ended at the next two rungs). Two evaluations where the answer is the hint or a neighbour,
/// instead of the bisection's four or five; the same answer for a monotone test. Pointwise bounds
/// keep the bisection: on integer samples their tests are far from monotone (a step that divides
/// the samples' spacing reproduces them), and hints there made the corpus's files 8% larger.
constexpr int kRoundingRung = 7;
constexpr int kLikelySplineRung = 3;
static_assert(kStepFactors[kRoundingRung] == 1.0, "the rounding rung is factor 1");
constexpr int kZstdLevel = 15;

/// How the encoder's coded payloads are entropy coded (the options' stage at kZstdLevel).
inline EntropyCoding entropyCoding(const EncoderOptions& opt) {
  return EntropyCoding{kZstdLevel, opt.entropy};
}
/// Candidates are compared coded at this zstd level, 40 times faster than kZstdLevel and within
/// about 2% of its bytes (lanes frames as they will be); the one kept is coded again at
/// kZstdLevel (recodeFrame).
constexpr int kTrialZstdLevel = 1;
inline EntropyCoding trialCoding(const EncoderOptions& opt) {
  return EntropyCoding{kTrialZstdLevel, opt.entropy};
}

/// A coded payload's entropy frame, coded at the trial level (`trial`: its frames' sizes; `tail`:
/// bytes after the frame; `values`: the values it codes), coded again at the file's level: the
/// same values, so the same error. A lanes frame that lanesFrameSure keeps is left as it is (zstd
/// at the file's level would rarely beat it by the 2% it must), and so is a dense frame (the
/// codes of noise: denseFrame in block_encoding.cpp).
void codeAtFileLevel(const EncoderOptions& opt, std::vector<uint8_t>& payload, size_t tail,
                     size_t values, FrameSizes trial);

/// The quantization step of ladder factor k for an error budget: factors of the step whose
/// rounding alone would spend the budget, 2 sqrt(3) x budget for an RMSE (uniform rounding's RMSE
/// is step / sqrt(12)), 2 x budget for a pointwise bound (its worst case is step / 2).
inline double ladderStep(BoundKind kind, double budget, double k) {
  return (kind == BoundKind::MaxError ? 2.0 : 2.0 * std::sqrt(3.0)) * budget * k;
}

/// The largest factor of kStepFactors (sorted descending) for which passes(factor) holds, by
/// bisection over the ladder (the error grows with the step); -1 when even the smallest fails. The
/// largest is tried first (a block that passes there costs one evaluation); the last call that
/// returned true is the answer's.
template <typename Passes>
int largestPassingStep(Passes&& passes) {
  const int n = int(sizeof(kStepFactors) / sizeof(kStepFactors[0]));
  if (passes(kStepFactors[0])) return 0;
  int fail = 0, pass = n;  // kStepFactors[fail] fails; [pass] passes (n: none known to)
  while (pass - fail > 1) {
    const int mid = (pass + fail) / 2;
    if (passes(kStepFactors[mid]))
      pass = mid;
    else
      fail = mid;
  }
  return pass < n ? pass : -1;
}

/// largestPassingStep when a likely answer is known (the rung another form of the same values
/// chose: their errors are those of a uniform rounding at the same step): that rung and its
/// neighbours towards the answer, usually two evaluations; the same answer as the bisection for
/// a monotone test. hint < 0: the bisection.
template <typename Passes>
int largestPassingStepFrom(int hint, Passes&& passes) {
  const int n = int(sizeof(kStepFactors) / sizeof(kStepFactors[0]));
  if (hint < 0 || hint >= n) return largestPassingStep(passes);
  if (passes(kStepFactors[hint])) {
    int j = hint - 1;
    while (j >= 0 && passes(kStepFactors[j])) --j;
    return j + 1;
  }
  int j = hint + 1;
  while (j < n && !passes(kStepFactors[j])) ++j;
  return j < n ? j : -1;
}

/// The error of a model on t's valid samples as a reader sees it: decodeBlockSamples (what
/// `afam verify` and the level decoder evaluate, in float32) of its decoded points (entry m, whose
/// samples are t's), against t.samples. FormatError when the shapes differ.
ErrorStats errorAsDecoded(const ModelEntry& m, const float* points, const BlockTask& t);

/// The entry's error and value range from the stored model's error on the block's samples.
void setError(BlockTask& t, const ErrorStats& es);

/// DS: the samples with their ghost layer are the payload (float32, uncoded); t.samples are left
/// for the caller to reuse.
void storeDownsampled(const BlockExtent& e, BlockTask& t);

/// A run's block coded as a residual on the step before's model (`before`, `model`: its entry and
/// control points as a reader decodes them): replaces t's stored form when the residual meets the
/// bound on t.samples, checked on what a reader decodes, in fewer bytes (residual_coding.cpp).
bool codeResidualIfSmaller(const FitContext& c, const BlockExtent& e, BlockFitter& fitter,
                           const ModelEntry& before, const FitResult& model, BlockTask& t);

/// Fits and stores one block of a spline mode (entry, stored bytes, statistics of the task);
/// t.samples are left (holes filled) for the caller to reuse or free.
/// Throws NumericError naming the block when its samples cannot be fitted.
void encodeBlock(const FitContext& c, const BlockExtent& e, BlockFitter& fitter, BlockTask& t);

}  // namespace afam
