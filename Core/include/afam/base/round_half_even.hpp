// SPDX-License-Identifier: BSD-3-Clause
// Rounding to the nearest integer, ties to even, without a libm call or a branch (host and device):
// the codec's quantization and a rounded interpolant's points (rounded_points.hpp).
#pragma once

#include "afam/base/host_device.hpp"

namespace afam {

/// roundHalfEven is exact below this magnitude (2^51).
constexpr double kRoundExact = 2251799813685248.0;

/// x rounded to the nearest integer, ties to even (nearbyint's result in the default rounding
/// mode), for |x| < kRoundExact: adding 1.5 * 2^52 leaves no fraction bits, subtracting it gives
/// the integer back. Loops over it vectorize; compiled without value-changing optimizations.
AFAM_HD double roundHalfEven(double x) {
  constexpr double kShift = 6755399441055744.0;  // 1.5 * 2^52
  return (x + kShift) - kShift;
}

}  // namespace afam
