// SPDX-License-Identifier: BSD-3-Clause
// Bounds on a fitted model's RMSE without evaluating the model on its samples: from the
// least-squares residual of the fit, or from a measured fit and the energy of a change of its
// control points. BlockFitter::fitWithin and BlockFitter::changeWithin decide a bound with them.
#pragma once

#include <cstddef>

namespace afam {

/// A range [lo, hi] of RMSE values (see rmseRange).
struct RmseRange {
  double lo = 0, hi = 0;
};

/// Range of the RMSE, as BlockFitter::error would measure it, of a fitted model on `count`
/// samples, from the least-squares identity |d - A c*|^2 = |d|^2 - c*^T A^T A c* (c* the exact
/// solution, which no other coefficients beat): sumOfSquares = |d|^2, energy = c^T A^T A c of the
/// computed solution, largestControl = max |control point| (its float32 rounding moves the model
/// by at most half an ulp of it). Rounding of the sums and of the measurement is allowed for.
RmseRange rmseRange(double sumOfSquares, double energy, double largestControl, size_t count);

/// Range of the measured RMSE of a least-squares fit's control points c changed to q, from the
/// fit's measured RMSE and changeEnergy = (c - q)^T A^T A (c - q): |d - A q|^2 = |d - A c|^2 + |A
/// (c - q)|^2 up to a cross term that only the float32 rounding of c makes non-zero. largestControl
/// = max |control point| of both.
RmseRange changedRmseRange(double fittedRmse, double changeEnergy, double largestControl,
                           size_t count);

}  // namespace afam
