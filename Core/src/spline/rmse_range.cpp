// SPDX-License-Identifier: BSD-3-Clause
// RMSE ranges from least-squares identities; see rmse_range.hpp.
#include "afam/spline/rmse_range.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>

namespace afam {

namespace {

/// The rounding that rmseRange and changedRmseRange allow for, on `count` samples of a model whose
/// largest |control point| is `largestControl`.
struct Rounding {
  double sums = 0;  ///< relative: sums of `count` terms and the solve, taken generously
  double controls =
      0;  ///< absolute: the float32 rounding of the control points moves the model
          ///< by at most half an ulp of the largest (a sample's basis weights are convex)
  double measuring = 0;  ///< absolute: the rounding of each model value when the error is measured
};

Rounding roundingOf(double largestControl, size_t count) {
  const double eps = std::numeric_limits<double>::epsilon();
  Rounding r;
  r.sums = 4 * double(count) * eps + 1e-11;
  r.controls = largestControl * (std::ldexp(1.0, -24) + 1e-11) + FLT_TRUE_MIN;
  r.measuring = 16 * eps * largestControl;
  return r;
}

/// The measured RMSE's range for a true mean squared error in [lo, hi].
RmseRange measuredRange(double lo, double hi, const Rounding& r) {
  RmseRange out;
  out.lo = std::max(0.0, std::sqrt(std::max(0.0, lo)) * (1 - r.sums) - r.measuring);
  out.hi = std::sqrt(std::max(0.0, hi)) * (1 + r.sums) + r.measuring;
  return out;
}

}  // namespace

RmseRange rmseRange(double sumOfSquares, double energy, double largestControl, size_t count) {
  const Rounding r = roundingOf(largestControl, count);
  const double n = double(std::max<size_t>(count, 1));
  const double slack = r.sums * (sumOfSquares + energy);
  const double residual = sumOfSquares - energy;  // |d - A c*|^2: the exact least-squares residual
  const double hi = std::sqrt(std::max(0.0, residual + slack) / n) + r.controls;
  return measuredRange((residual - slack) / n, hi * hi, r);
}

RmseRange changedRmseRange(double fittedRmse, double changeEnergy, double largestControl,
                           size_t count) {
  const Rounding r = roundingOf(largestControl, count);
  const double n = double(std::max<size_t>(count, 1));
  const double fLo = std::max(0.0, fittedRmse * (1 - r.sums) - r.measuring);
  const double fHi = fittedRmse * (1 + r.sums) + r.measuring;
  const double qLo = changeEnergy * (1 - r.sums) / n, qHi = changeEnergy * (1 + r.sums) / n;
  // |d - A q|^2 = |d - A c|^2 + |A (c - q)|^2 + 2 <A (c* - c), A (c - q)>: the exact residual
  // d - A c* is orthogonal to every A x, and |A (c* - c)| / sqrt(n) <= the float32 rounding.
  const double cross = 2 * r.controls * std::sqrt(qHi);
  return measuredRange(fLo * fLo + qLo - cross, fHi * fHi + qHi + cross, r);
}

}  // namespace afam
