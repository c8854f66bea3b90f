// SPDX-License-Identifier: BSD-3-Clause
// The search for a block's control-point counts: the paper's scalar NCP* (the same count on every
// axis, clamped per axis) and a per-axis refinement for blocks whose samples vary much less along
// some axes than along others (layers, sheets, thin structures).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "afam/format/afam_file.hpp"

namespace afam {

class BlockFitter;
struct FitResult;

enum class SearchMethod : uint8_t { Fast = 0, Exhaustive = 1 };

/// What is known of a fit before it is made.
enum class Verdict : int8_t { Unknown = -1, Fails = 0, Passes = 1 };

/// Verdicts on some of one block's NCPs at one RMSE bound, given ahead of its search (from a batch
/// of least-squares residuals, ncp_verdicts.hpp): searchNcp and refineNcpPerAxis fit only the NCPs
/// they have no verdict for, and the one they end at; should that fit contradict a verdict, they
/// search again by fitting. So verdicts change how many fits a search makes, never what it may
/// return: a fit that keeps the bound.
struct NcpVerdicts {
  double bound = -1;  ///< the RMSE bound they answer for (the searches use them at it only)
  std::vector<std::pair<std::array<int, 3>, Verdict>> known;
  Verdict of(std::array<int, 3> ncp) const;
  /// of(ncp) where the verdicts answer for the bound `asked`, else Unknown.
  Verdict at(std::array<int, 3> ncp, double asked) const {
    return asked == bound ? of(ncp) : Verdict::Unknown;
  }
  void set(std::array<int, 3> ncp, Verdict verdict);
};

/// The scalar search's questions alone (see encoder.hpp for how Fast asks them): the smallest NCP
/// in [lo, hi] it finds that `pass` accepts, hi + 1 when none. `pass` is asked once per NCP.
int smallestPassingNcp(int lo, int hi, SearchMethod method, int window,
                       const std::function<bool(int)>& pass);

/// In-level search on one block's samples: NCP* = the smallest scalar NCP in [p+1, n] (n the
/// block's largest sample count, clamped per axis by clampNcp) whose RMSE is <= bound; n if none
/// is. Returns NCP* and the fit at NCP* in `result` (its error measured on the samples); `fits`
/// counts the fits performed. Each candidate is judged by BlockFitter::fitWithin, which gives the
/// answer measuring its error would. Fast and Exhaustive give the same NCP* (see encoder.hpp for
/// how Fast searches). With a pointwise bound (BoundKind::MaxError) a candidate must keep every
/// sample within `bound` (measured; fitWithin's RMSE above the bound rejects it without).
int searchNcp(BlockFitter& fitter, const float* samples, std::array<int, 3> n, int degree,
              double bound, SearchMethod method, int window, FitResult& result, int64_t& fits,
              BoundKind kind = BoundKind::Rmse, const NcpVerdicts* verdicts = nullptr);

/// Per-axis refinement of a passing fit: for each axis whose samples are much smoother than the
/// roughest axis (mean squared second difference at most kAnisotropy times smaller), the smallest
/// NCP on that axis, the others fixed, whose fit still meets `bound` (bisection between p+1 and the
/// current NCP). Smoothest axis first. `result` must meet the bound on entry and still does on
/// return (its error measured), with a control-point count never larger. Returns true when an axis
/// was reduced. `roughness`: axisRoughness of the samples where the caller has it.
bool refineNcpPerAxis(BlockFitter& fitter, const float* samples, std::array<int, 3> n, int degree,
                      double bound, FitResult& result, int64_t& fits,
                      BoundKind kind = BoundKind::Rmse, const NcpVerdicts* verdicts = nullptr,
                      const std::array<double, 3>* roughness = nullptr);

/// The refinement's questions alone: from `start` (passing), for each axis at most 1/kAnisotropy
/// as rough as the roughest (`rough`, axisRoughness), smoothest first, the smallest NCP on that
/// axis that `pass` accepts, the others fixed (bisection between p+1 and the current NCP).
std::array<int, 3> fewerPointsPerAxis(const std::array<double, 3>& rough, std::array<int, 3> start,
                                      std::array<int, 3> n, int degree,
                                      const std::function<bool(std::array<int, 3>)>& pass);

/// A floor under the RMSE of every model of the fewest control points (NCP = p + 1 on every axis,
/// clampNcp's lowest: along each axis a polynomial of that axis's effective degree): the least-
/// squares residual of every `stride`-th x-line (in y and z) by such polynomials in x, over all
/// the block's samples. Each model is such a polynomial along each x-line, so its squared error on
/// those lines is at least that residual. A few passes over a share of the samples, where a fit
/// reads them all several times: the search's first question (p + 1) needs no fit where the floor
/// is above its bound (fewestPointsFail). `squares`, where given, gains the sum of the squared
/// samples of the lines read.
double fewestPointsRmseFloor(const float* samples, std::array<int, 3> n, int degree, int stride = 4,
                             double* squares = nullptr);

/// Sets the verdict Fails for the fewest control points in `verdicts` (answering for `bound`: any
/// verdicts for another bound are dropped) where fewestPointsRmseFloor is above the RMSE bound
/// beyond rounding; returns whether it did.
bool fewestPointsFail(const float* samples, std::array<int, 3> n, int degree, double bound,
                      NcpVerdicts& verdicts);

/// The most an interpolating spline's control points exceed its samples in magnitude, on one axis
/// of n samples (NCP = n, the degree reduced by effectiveDegree): the infinity norm of the inverse
/// of its collocation matrix (computed once per thread for each (n, degree)).
double interpolationGain(int n, int degree);

/// Sets the verdict Passes for NCP = n on every axis (the interpolating spline) in `verdicts`
/// (answering for `bound`, as fewestPointsFail) where that spline's float32 control points are
/// sure to keep the RMSE bound: its error is their rounding (at most 2^-24 of the largest, the
/// samples' largest magnitude times the product of the axes' interpolationGain) and the solve's
/// (far below), and twice both is within the bound. Returns whether it did.
bool interpolantPasses(const float* samples, std::array<int, 3> n, int degree, double bound,
                       NcpVerdicts& verdicts);

/// Roughness ratio between the roughest and an axis at which refineNcpPerAxis tries that axis.
constexpr double kAnisotropy = 8.0;

/// Mean squared second difference of the samples along each axis (0 for an axis of < 3 samples).
/// `smallIntegers`: every sample is an integer of magnitude below 1024 (a volume stored in bytes,
/// at its own grid): the differences and their squares are then exact in float, taken eight at
/// a time, and the sums are the same doubles.
std::array<double, 3> axisRoughness(const float* samples, std::array<int, 3> n,
                                    bool smallIntegers = false);

}  // namespace afam
