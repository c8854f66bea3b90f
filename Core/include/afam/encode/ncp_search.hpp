// SPDX-License-Identifier: BSD-3-Clause
// The search for a block's control-point counts: the paper's scalar NCP* (the same count on every
// axis, clamped per axis) and a per-axis refinement for blocks whose samples vary much less along
// some axes than along others (layers, sheets, thin structures).
#pragma once

#include <array>
#include <cstdint>

#include "afam/format/afam_file.hpp"

namespace afam {

class BlockFitter;
struct FitResult;

enum class SearchMethod : uint8_t { Fast = 0, Exhaustive = 1 };

/// In-level search on one block's samples: NCP* = the smallest scalar NCP in [p+1, n] (n the
/// block's largest sample count, clamped per axis by clampNcp) whose RMSE is <= bound; n if none
/// is. Returns NCP* and the fit at NCP* in `result` (its error measured on the samples); `fits`
/// counts the fits performed. Each candidate is judged by BlockFitter::fitWithin, which gives the
/// answer measuring its error would. Fast and Exhaustive give the same NCP* (see encoder.hpp for
/// how Fast searches). With a pointwise bound (BoundKind::MaxError) a candidate must keep every
/// sample within `bound` (measured; fitWithin's RMSE above the bound rejects it without).
int searchNcp(BlockFitter& fitter, const float* samples, std::array<int, 3> n, int degree,
              double bound, SearchMethod method, int window, FitResult& result, int64_t& fits,
              BoundKind kind = BoundKind::Rmse);

/// Per-axis refinement of a passing fit: for each axis whose samples are much smoother than the
/// roughest axis (mean squared second difference at most kAnisotropy times smaller), the smallest
/// NCP on that axis, the others fixed, whose fit still meets `bound` (bisection between p+1 and the
/// current NCP). Smoothest axis first. `result` must meet the bound on entry and still does on
/// return (its error measured), with a control-point count never larger. Returns true when an axis
/// was reduced.
bool refineNcpPerAxis(BlockFitter& fitter, const float* samples, std::array<int, 3> n, int degree,
                      double bound, FitResult& result, int64_t& fits,
                      BoundKind kind = BoundKind::Rmse);

/// Roughness ratio between the roughest and an axis at which refineNcpPerAxis tries that axis.
constexpr double kAnisotropy = 8.0;

/// Mean squared second difference of the samples along each axis (0 for an axis of < 3 samples).
std::array<double, 3> axisRoughness(const float* samples, std::array<int, 3> n);

}  // namespace afam
