// SPDX-License-Identifier: BSD-3-Clause
// Interpolants whose control points are rounded to a step (index flag bit 14, docs/FORMAT.md).
// An interpolant stores its block's samples coded; its model is the spline fitted through them,
// whose control points are arbitrary floats. A rounded interpolant's payload ends with one more
// byte j, and every fitted point c becomes k q, k = c / q rounded (pointCode), q the coded samples'
// step (the payload's first 8 bytes) divided by 2^j. A cache then keeps the model as a table of its
// values and a 1- or 2-byte code a point (compact_form.hpp) instead of float32: an 8-bit scan's
// interpolants in a quarter of the bytes. The encoder chooses j where the rounded model still
// meets the bound on the block's samples (the B-spline basis is a convex combination, so no model
// value moves more than q / 2), and writes no j where none does.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include "afam/base/errors.hpp"
#include "afam/base/host_device.hpp"
#include "afam/base/round_half_even.hpp"

namespace afam {

/// Bytes the rounding adds to a payload: j, its last byte.
constexpr size_t kRoundedPointsBytes = 1;
/// Largest j a reader takes: q = step / 2^40 rounds points far below float32's resolution for any
/// value the step could code.
constexpr int kMaxPointShift = 40;
/// Codes are exact while |c / q| stays below this (double's integers, with room for rounding).
constexpr double kMaxPointCode = 1125899906842624.0;  // 2^50

/// The step q of a rounded interpolant's points: its coded samples' step / 2^j, j the payload's
/// last byte. FormatError naming `where` when the step is not a positive finite number or
/// j > kMaxPointShift.
inline double roundedPointStep(const uint8_t* stored, size_t bytes, const char* where) {
  double step = 0;
  if (bytes > 8) std::memcpy(&step, stored, 8);
  const int shift = bytes > 8 ? stored[bytes - 1] : 0;
  if (!(step > 0) || !std::isfinite(step) || shift > kMaxPointShift)
    throw FormatError(std::string(where) + ": rounded interpolant's point step (step " +
                      std::to_string(step) + ", shift " + std::to_string(shift) +
                      ") is not a positive step / 2^j, j <= " + std::to_string(kMaxPointShift));
  return std::ldexp(step, -shift);
}

/// A point's code at step q: c * (1 / q) in binary64, rounded to the nearest integer, ties to
/// even (block_codec.cpp, compiled without FMA contraction, so that every build codes alike; a
/// product, not a quotient, as decoding rounds every point of a block).
int64_t pointCode(float c, double q);
/// Point c rounded to step q, as roundPoints rounds every point (`inverse`: 1 / q, computed once
/// by the caller): k q in binary64 to float32, k = c * inverse rounded to the nearest integer, ties
/// to even; k into *code. False (and the value of k = 0) when c is not finite or lies
/// kMaxPointCode steps or more from 0, or when k q is beyond float32. Host and device.
AFAM_HD bool roundedPoint(float c, double q, double inverse, float* value, double* code) {
  const double x = double(c) * inverse;
  const bool inRange = (x < 0 ? -x : x) < kMaxPointCode;  // false for NaN too
  const double k = roundHalfEven(inRange ? x : 0.0);
  const float v = static_cast<float>(k * q);
  *value = v;
  *code = k;
  return inRange & ((v < 0 ? -v : v) <= 3.40282346638528859812e+38f);
}

/// The float a reader keeps for code k.
inline float pointValue(int64_t k, double q) { return static_cast<float>(double(k) * q); }

/// Rounds `count` points to step q in place, as pointCode and pointValue do (their codes into k
/// unless it is null). False, with the points not all as pointValue gives them, when one is not
/// finite or lies kMaxPointCode steps or more from 0, or rounds to a value beyond float32.
bool roundPoints(float* points, size_t count, double q, int64_t* k);

/// roundPoints keeping only the span of the codes (largest less smallest; 0 where it fails).
bool roundPointsSpan(float* points, size_t count, double q, uint64_t& span);

}  // namespace afam
