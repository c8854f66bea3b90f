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
#include "afam/encode/step_ladder.hpp"
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
  /// Whether a block's sample may be missing (NaN): false where the volume's scan found none, so
  /// that no block looks for one.
  bool mayMiss = true;
  /// Whether every sample of the level's blocks is an integer of magnitude below 1024 (the finest
  /// level of a volume stored in bytes, with none missing): axisRoughness's exact float path.
  bool smallIntegers = false;
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
