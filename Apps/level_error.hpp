// SPDX-License-Identifier: BSD-3-Clause
// How far a decoded level is from the original volume: the one measure behind
// `afam verify --against` and `afam compare-codecs` (and the ZFP side of the latter).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>

#include "afam/encode/encoder.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/render/level_decode.hpp"

namespace afam::cli {

/// RMSE and max absolute error over pairs of values, accumulated in double. A missing sample
/// (NaN) is counted as such when both sides miss it, and as a mask mismatch when one side does.
struct ErrorAccumulator {
  double sumSquares = 0, maxError = 0;
  int64_t count = 0;  ///< valid samples compared
  int64_t missing = 0, maskMismatches = 0;
  void add(const float* decoded, const float* reference, int64_t n) {
    for (int64_t k = 0; k < n; ++k) {
      const bool lost = std::isnan(decoded[k]), absent = std::isnan(reference[k]);
      if (lost || absent) {
        ++(lost == absent ? missing : maskMismatches);
        continue;
      }
      const double d = double(decoded[k]) - double(reference[k]);
      sumSquares += d * d;
      maxError = std::max(maxError, std::fabs(d));
      ++count;
    }
  }
  double rmse() const { return count > 0 ? std::sqrt(sumSquares / double(count)) : 0.0; }
};

/// Decodes `level` of `file` block by block (afam::decodeLevelBox over each block's own samples)
/// and compares it with the original volume sampled at the same positions (BlockRowReader: the
/// Partition's sampling rule), each sample of the level grid once. At the finest level that is
/// every voxel of the volume once. Streams one row of blocks at a time. `progress` gets fractions
/// in [0, 1]. Throws InvalidArgument when the dims differ or the level is out of range.
ErrorAccumulator measureLevelError(const AfamFile& file, VolumeSource& original, int level,
                                   const std::function<void(double)>& progress = {});

}  // namespace afam::cli
