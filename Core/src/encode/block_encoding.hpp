// SPDX-License-Identifier: BSD-3-Clause
// One micro-block's model, chosen and stored by the encoder (private to Core): the fit with the
// bound check, and the compact representations (constant, coded spline, coded samples).
#pragma once

#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "afam/encode/encoder.hpp"
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
  ModelEntry entry;
  std::vector<uint8_t> stored;  ///< the payload as the file stores it (entry.storedSize bytes)
  int ncpStar = 0;
  int64_t fits = 0;
  bool complex = false;
  bool refit = false;  ///< skipped the search by cross-level reuse, missed the bound, searched
  bool exact = false;  ///< stored as its samples (no NCP met the bound)
  bool reducedDegree = false;  ///< an axis has fewer samples than the degree needs
  double rmse = 0,
         maxError = 0;  ///< of the stored model on the block's samples (the entry keeps floats)
};

struct FitContext {
  const EncoderOptions& opt;
  double bound;
  int level;
  std::string sourceName;
};

/// DS: the samples with their ghost layer are the payload (float32, uncoded).
void storeDownsampled(const BlockExtent& e, BlockTask& t);

/// Fits and stores one block of a spline mode (entry, stored bytes, statistics of the task).
/// Throws NumericError naming the block when its samples cannot be fitted.
void encodeBlock(const FitContext& c, const BlockExtent& e, BlockFitter& fitter, BlockTask& t);

}  // namespace afam
