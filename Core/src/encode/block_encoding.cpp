// SPDX-License-Identifier: BSD-3-Clause
#include "block_encoding.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <sstream>

#include "afam/base/any_nan.hpp"
#include "afam/base/cpu_features.hpp"
#include "afam/encode/first_step_blocks.hpp"
#include "afam/format/block_codec.hpp"
#include "afam/format/block_decode.hpp"
#include "afam/format/block_mask.hpp"
#include "afam/format/rounded_points.hpp"
#include "afam/search/ncp_search.hpp"
#include "hole_fill.hpp"

namespace afam {

namespace {

// Compact mode: the spline is fitted to kFitShare of the bound, the rest of the budget (in
// quadrature) goes to the quantization of its control points. Steps are tried from the largest
// (the basis averages independent rounding errors, so the model moves less than the points) down.
// The largest step whose reconstruction meets the bound is kept: a larger step is fewer bits, and a
// block whose error budget is not spent gains nothing from it. Factors of 2 sqrt(3) x budget (the
// step whose uniform rounding error alone would spend it), tried from the largest.
constexpr double kFitShare = 0.9;

template <typename T>
std::vector<uint8_t> bytesOf(const std::vector<T>& v) {
  std::vector<uint8_t> out(v.size() * sizeof(T));
  if (!out.empty()) std::memcpy(out.data(), v.data(), out.size());
  return out;
}

/// The valid samples' mask words of a task, nullptr when every sample is valid.
const uint32_t* validOf(const BlockTask& t) { return t.mask.empty() ? nullptr : t.mask.data(); }

/// Error of model values (on the block's sample grid; model(i) gives value i) against the valid
/// samples; min/max of the model there.
template <typename Model>
AFAM_TARGET_AVX2 ErrorStats compareAvx2(const Model& model, const std::vector<float>& s,
                                        const uint32_t* valid) {
  return errorOnValidOf(model, s.data(), s.size(), valid);
}
template <typename Model>
ErrorStats compare(const Model& model, const std::vector<float>& s, const uint32_t* valid) {
  if (cpuHasAvx2()) return compareAvx2(model, s, valid);
  return errorOnValidOf(model, s.data(), s.size(), valid);
}

/// The block's samples themselves as a degree-1 spline with NCP = n per axis: its implied knots
/// put the control points on the sample parameters, so it reproduces every (float) sample exactly.
void exactModel(const BlockExtent& e, const BlockTask& t, FitResult& fr) {
  fr.ncp = e.samples;
  for (int a = 0; a < 3; ++a) fr.degree[a] = effectiveDegree(1, e.samples[a]);
  fr.control = t.samples;
  fr.error = compare([&t](size_t i) { return t.samples[i]; }, t.samples, validOf(t));
}

/// Fits one block to `bound`: the searched NCP* (every block of a bounded mode searches), or the
/// fixed mode's NCP without a search. In bounded modes the error is then checked on the block's
/// own samples: one that misses the bound even at NCP = n is the exact model (t.exact).
void fitBlock(const FitContext& c, const BlockExtent& e, BlockFitter& fitter, double bound,
              BlockTask& t, FitResult& fr) {
  Int3 degs{};
  int nmax = 1;
  for (int a = 0; a < 3; ++a) {
    degs[a] = effectiveDegree(c.opt.degree, e.samples[a]);
    nmax = std::max(nmax, e.samples[a]);
  }
  const int lo = std::min(c.opt.degree + 1, nmax);
  const BoundKind kind = c.opt.boundKind;
  auto search = [&]() {
    if (kind == BoundKind::Rmse && t.mask.empty()) {  // the first two questions without a fit
      fewestPointsFail(t.samples.data(), e.samples, c.opt.degree, bound, t.verdicts);
      interpolantPasses(t.samples.data(), e.samples, c.opt.degree, bound, t.verdicts);
    }
    t.ncpStar = searchNcp(fitter, t.samples.data(), e.samples, c.opt.degree, bound, c.opt.search,
                          c.opt.fastWindow, fr, t.fits, kind, &t.verdicts);
    t.complex = t.ncpStar > lo;
    if (c.opt.perAxisNcp && t.complex && keeps(kind, fr.error, bound))
      refineNcpPerAxis(fitter, t.samples.data(), e.samples, c.opt.degree, bound, fr, t.fits, kind,
                       &t.verdicts, t.roughness ? &*t.roughness : nullptr);
  };
  if (t.search) {
    search();
  } else {
    const Int3 ncp = c.opt.fixedNcp > 0 ? clampNcp(c.opt.fixedNcp, e.samples, degs) : e.samples;
    fitter.fitInto(t.samples.data(), e.samples, ncp, c.opt.degree, true, fr);
    ++t.fits;
    t.ncpStar = std::max({ncp[0], ncp[1], ncp[2]});
  }
  if (!bounded(c.opt.mode)) return;
  if (!fr.errorMeasured) fitter.measure(t.samples.data(), e.samples, fr);
  if (keeps(kind, fr.error, bound)) return;
  exactModel(e, t, fr);
  t.exact = true;
  t.complex = true;
}

/// Float32 payload of a fitted model (Spline, or Samples for the exact model).
void storeFloat(FitResult& fr, bool exact, BlockTask& t) {
  ModelEntry& m = t.entry;
  m.kind = exact ? BlockKind::Samples : BlockKind::Spline;
  m.coded = false;
  m.integerCoded = m.lanesCoded = m.roundedPoints = false;
  m.ncp = fr.ncp;
  m.degree = fr.degree;
  setError(t, fr.error);
  t.measuredAsRead = false;
  t.stored = bytesOf(fr.control);
  m.storedSize = t.stored.size();
}

/// A candidate stored form of the block.
struct Candidate {
  BlockKind kind = BlockKind::Spline;
  Int3 ncp{}, degree{};
  /// On the samples; of a coded spline the ladder passed, maybe only a bound on its RMSE (the kept
  /// candidate's is measured as read: checkAsRead).
  ErrorStats error;
  std::vector<uint8_t> bytes;
  bool roundedPoints = false;  ///< an interpolant whose bytes end with its points' shift
  FrameSizes frames;           ///< the entropy frames formed when it was coded (recodeFrame)
  /// `error` is of the model a reader decodes from `bytes` (BlockTask::measuredAsRead).
  bool measuredAsRead = false;
  /// A coded interpolant's samples as `bytes` decode (its ladder's kept quantization, valid until
  /// that form's next ladder on the thread: laddered), for checkInterpolant.
  const HugePageVector<float>* decoded = nullptr;
};

/// The sum over the samples of (sample - m)^2 (kSquares) or of the samples, in four lanes (sample
/// i in lane i mod 4, the lanes added pairwise), compiled also for AVX2 (four doubles a vector,
/// no FMA: the same sums) and chosen at run time.
template <bool kSquares>
__attribute__((always_inline)) inline double laneSum(const std::vector<float>& s, double m) {
  DoubleQuad lane = {0, 0, 0, 0};
  size_t i = 0;
  for (; i + 4 <= s.size(); i += 4) {
    const DoubleQuad v = {double(s[i]), double(s[i + 1]), double(s[i + 2]), double(s[i + 3])};
    if (kSquares)
      lane += (v - m) * (v - m);
    else
      lane += v;
  }
  double sum = (lane[0] + lane[1]) + (lane[2] + lane[3]);
  for (; i < s.size(); ++i) {
    const double v = double(s[i]);
    sum += kSquares ? (v - m) * (v - m) : v;
  }
  return sum;
}
template <bool kSquares>
AFAM_TARGET_AVX2 double laneSumAvx2(const std::vector<float>& s, double m) {
  return laneSum<kSquares>(s, m);
}
template <bool kSquares>
double sumOfLanes(const std::vector<float>& s, double m) {
  return cpuHasAvx2() ? laneSumAvx2<kSquares>(s, m) : laneSum<kSquares>(s, m);
}

/// The RMSE of the value m on all the samples.
double rmseAround(const std::vector<float>& s, double m) {
  const double sum = sumOfLanes<true>(s, m);
  return std::sqrt(sum / double(std::max<size_t>(s.size(), 1)));
}

/// The mean of the valid samples (every sample where `valid` is null: laneSum).
double meanOf(const std::vector<float>& s, const uint32_t* valid) {
  if (valid) {
    double sum = 0;
    size_t used = 0;
    for (size_t i = 0; i < s.size(); ++i)
      if (((valid[i >> 5] >> (i & 31)) & 1u) != 0) {
        sum += double(s[i]);
        ++used;
      }
    return sum / double(used);
  }
  const double sum = sumOfLanes<false>(s, 0.0);
  return sum / double(std::max<size_t>(s.size(), 1));
}

/// Whether no constant can keep the bound, by a floor under every constant's error: half the
/// samples' range (the worst error of their middle), or their RMSE around their mean (where every
/// sample is valid). Clear of rounding by a margin: a block near the bound is measured.
bool noConstantFits(double floor, double bound, double scale) {
  return floor > bound * (1 + 1e-6) + 1e-9 * std::fabs(scale);
}

bool constantFits(const BlockExtent& e, const std::vector<float>& s, const uint32_t* valid,
                  int degree, double bound, BoundKind kind, Candidate& out) {
  float c;
  if (kind == BoundKind::MaxError) {  // the middle of the range: the smallest worst error
    const ErrorStats range = compare([&s](size_t i) { return s[i]; }, s, valid);
    if (noConstantFits(0.5 * (range.maxValue - range.minValue), bound, 0)) return false;
    c = float(0.5 * (range.minValue + range.maxValue));
  } else {  // the mean: the smallest RMSE
    const double mean = meanOf(s, valid);
    if (!valid && noConstantFits(rmseAround(s, mean), bound, mean)) return false;
    c = float(mean);
  }
  const ErrorStats es = compare([c](size_t) { return c; }, s, valid);
  if (!keeps(kind, es, bound)) return false;
  out.kind = BlockKind::Constant;
  for (int a = 0; a < 3; ++a) {
    out.degree[a] = effectiveDegree(degree, e.samples[a]);
    out.ncp[a] = out.degree[a] + 1;
  }
  out.error = es;
  out.bytes.resize(4);
  std::memcpy(out.bytes.data(), &c, 4);
  return true;
}

/// How far over the budget a rung's rounding, scaled from the rung measured before, may be
/// predicted and the rung still be measured (largestPassingStepGuided). Wider than the samples'
/// kGuidedMargin: a spline's rounding is that of its control points seen through its basis, fewer
/// values than samples, so that from one rung to the next it strays further from proportion (the
/// head made 301x370x316 at 1e-2: 1.05 and 1.08 stopped a few blocks a rung short, 1.12 wrote
/// the walk's bytes). At coarse steps, where most predictions round to zero, the rounding grows
/// more slowly than the step and the guide may stop a rung short (the same head at 3e-2: 60 bytes
/// of 50,572 more, even at 1.2); every step kept still keeps the bound.
constexpr double kSplineGuidedMargin = 1.12;

/// A spline's control points quantized in one form at the largest step of the ladder that keeps
/// the model within the bound (ladderSpline), kept until the form is coded.
struct LadderedSpline {
  QuantizedValues kept;
  ErrorStats passed;  ///< the model's error at that step (maybe only a bound on its RMSE)
};
LadderedSpline& ladderedSpline(Predictor form) {
  thread_local LadderedSpline integer, dbl;
  return isIntegerForm(form) ? integer : dbl;
}

/// The fitted spline's control points, Lorenzo-predicted in the given form, quantized at the
/// largest step of the ladder that keeps the model within the bound, into ladderedSpline(form);
/// `rung`: the ladder's hint in, its answer out.
bool ladderSpline(const FitResult& fr, const std::vector<float>& s, Int3 n, double bound,
                  BoundKind kind, Predictor form, BlockFitter& fitter, int& rung) {
  // What quantization may spend: the rest of an RMSE in quadrature; of a pointwise bound, what
  // the fit's worst sample leaves (the model moves by at most step / 2 anywhere).
  const double budget =
      kind == BoundKind::MaxError
          ? bound - fr.error.maxError
          : std::sqrt(std::max(0.0, bound * bound - fr.error.rmse * fr.error.rmse));
  if (!(budget > 0)) return false;
  // The trial step's model (its points copied from the quantization into the thread's q, which
  // keeps its buffer between blocks).
  thread_local FitResult q;
  q.ncp = fr.ncp;
  q.degree = fr.degree;
  q.error = fr.error;
  q.errorMeasured = fr.errorMeasured;
  bool lattice = true;
  LadderedSpline& l = ladderedSpline(form);
  thread_local QuantizedValues trial;  // the step being tried
  // Whether factor k's step keeps the bound; under an RMSE also what the quantization adds to
  // the fit's error in quadrature (`added`: the ladder's guide, <= budget where it keeps it).
  double added = 0;
  auto passes = [&](double k) {
    const double step = ladderStep(kind, budget, k);
    if (!quantizeValues(fr.control.data(), fr.ncp, step, form, trial)) {
      lattice = false;
      added = std::numeric_limits<double>::infinity();
      return false;
    }
    q.control.assign(trial.reconstructed.begin(), trial.reconstructed.end());
    if (kind == BoundKind::MaxError) {
      q.errorMeasured = false;
      fitter.measure(s.data(), n, q);
      if (!keeps(kind, q.error, bound)) return false;
    } else {
      const bool within = fitter.changeWithin(s.data(), n, fr, q, bound);
      const double quadrature =
          std::sqrt(std::max(0.0, q.error.rmse * q.error.rmse - fr.error.rmse * fr.error.rmse));
      added = within ? std::min(quadrature, budget) : std::max(quadrature, budget * (1 + 1e-12));
      if (!within) return false;
    }
    l.passed = q.error;
    std::swap(trial, l.kept);
    return true;
  };
  // Under an RMSE the rounding's share grows in proportion to the step: the ladder guided by it
  // (largestPassingStepGuided, usually one quantization where the walk took two); a pointwise
  // bound's worst sample does not, and walks.
  const int best = kind == BoundKind::Rmse ? largestPassingStepGuided(
                                                 rung, budget,
                                                 [&](double k) {
                                                   passes(k);
                                                   return added;
                                                 },
                                                 kSplineGuidedMargin)
                                           : largestPassingStepFrom(rung, passes);
  rung = best;
  // The coder codes what the ladder decided on: its verdict stands.
  return best >= 0 && lattice && l.kept.step == ladderStep(kind, budget, kStepFactors[best]);
}

/// The laddered spline of `form` (ladderSpline) coded; the error the entry stores is measured as
/// a reader decodes the kept candidate (checkAsRead).
bool codeLadderedSpline(const FitResult& fr, Predictor form, double bound, BoundKind kind,
                        EntropyCoding coding, Candidate& out) {
  LadderedSpline& l = ladderedSpline(form);
  std::vector<uint8_t> bytes;
  const FrameSizes frames = encodeQuantized(l.kept, coding, bytes);
  out = Candidate{BlockKind::Spline, fr.ncp, fr.degree, l.passed, std::move(bytes), false, frames};
  return keeps(kind, out.error, bound);
}

/// Keeps the smaller of two coded candidates, the integer form unless the double form saves more
/// than 2% of its bytes (the integer form decodes about 2.7x faster; block_codec.hpp). At coarse
/// steps (a step of a few noise sigmas) the double form can code noticeably smaller, as its
/// predictions keep the fractions the integer form rounds away.
/// Whether a double form of `dbl` bytes wins over an integer form of `integer` bytes.
bool doubleFormWins(size_t dbl, size_t integer) {
  return double(dbl) < kDoubleFormShare * double(integer);
}

bool keepSmallerForm(bool hasInteger, Candidate& integer, bool hasDouble, Candidate& dbl,
                     Candidate& out) {
  if (hasDouble && (!hasInteger || doubleFormWins(dbl.bytes.size(), integer.bytes.size()))) {
    out = std::move(dbl);
    return true;
  }
  if (!hasInteger) return false;
  out = std::move(integer);
  return true;
}

/// Whether a spline's double form is neither laddered nor coded, its integer form coded
/// (`integer`, its trial frames): where lorenzoFormCannotWin judges, at the integer form's step
/// (where the double form's ladder, started there, ends on nearly every spline: 8,166 of the 8,173
/// of the head made 1204x1480x1264), that the double form cannot win.
bool doubleSplineSpared(const FitResult& fr, const Candidate& integer) {
  return lorenzoFormCannotWin(ladderedSpline(Predictor::IntegerLorenzo).kept, integer.bytes,
                              integer.frames, fr.control.data(),
                              ladderedSpline(Predictor::Lorenzo).kept);
}

bool codeSpline(const FitResult& fr, const std::vector<float>& s, Int3 n, double bound,
                BoundKind kind, EntropyCoding coding, BlockFitter& fitter, Candidate& out) {
  constexpr Predictor integerForm = Predictor::IntegerLorenzo, doubleForm = Predictor::Lorenzo;
  // The integer form's rung, then the double form's from it: the likely one.
  int rung = kind == BoundKind::Rmse ? kLikelySplineRung : -1;
  Candidate integer, dbl;
  const bool hasInteger = ladderSpline(fr, s, n, bound, kind, integerForm, fitter, rung) &&
                          codeLadderedSpline(fr, integerForm, bound, kind, coding, integer);
  const bool hasDouble = !(hasInteger && doubleSplineSpared(fr, integer)) &&
                         ladderSpline(fr, s, n, bound, kind, doubleForm, fitter, rung) &&
                         codeLadderedSpline(fr, doubleForm, bound, kind, coding, dbl);
  return keepSmallerForm(hasInteger, integer, hasDouble, dbl, out);
}

/// A model's error on the samples for a bound of `kind`, as a reader measures it: under a
/// pointwise bound on the float32 values a reader evaluates (evaluateOnGrid, decodeBlockSamples'
/// evaluation), where the fitter's own evaluation (BlockFitter::error, its sums fused) may differ
/// in the last bits that decide the bound (the bound sweep's pointwise bounds at 1e-5 found
/// interpolants 0.01-0.1% over it as read); under an RMSE the fitter's, which agrees far below it.
ErrorStats errorForBound(BlockFitter& fitter, BoundKind kind, const std::vector<float>& s, Int3 n,
                         const FitResult& model, const uint32_t* valid) {
  if (kind != BoundKind::MaxError) return fitter.error(s.data(), n, model);
  thread_local std::vector<float> grid;  // kept between blocks, as its pages
  fitter.evaluateOnGrid(model, n, grid);
  return errorOnValid(grid.data(), s.data(), grid.size(), valid);
}

/// How much an interpolant's rounded points may add to its error: 1% (the rounding's own
/// error, about 0.14 of the model's in quadrature), so that files keep the quality they had at the
/// same bytes (equal-error comparisons with other codecs see the same file) rather than spend the
/// bound's headroom on memory.
constexpr double kRoundingGrowth = 1.01;
/// Shifts j (q = the samples' step / 2^j), 0 to kLastShift. Under a pointwise bound, and where the
/// bound leaves rounding little room (kGuidedRoom), they are tried from kFirstShift towards larger
/// steps while they pass, else towards smaller ones. Measured on noisy scans, j = 2 passes most.
constexpr int kFirstShift = 2, kLastShift = 10;
/// Under an RMSE bound, rounding the points to q adds about kRoundingGain q^2 / 12 to the squared
/// error (uniform rounding of each point, the sum of its squared basis weights at the samples):
/// measured 0.17-0.26 on the corpus's quadratic interpolants at 1e-2. The shift first measured is
/// the largest step this predicts within the allowance; the search then goes by the measured gain
/// (largestPassingGuided over q^2), one evaluation where the walk from kFirstShift took two.
constexpr double kRoundingGain = 0.21;
/// The guided search only where the allowance leaves rounding at least this share of the squared
/// error (the bound at least 0.5% above it; kRoundingGrowth leaves 2%): closer to the bound, what
/// rounding adds is within the noise of its correlation with the samples' own rounding (a test
/// field's blocks at 0.99991 of the bound measured more at shift 6 than at 7, and the walk from
/// kFirstShift found 3 or 4 passing, codes of 1 or 2 bytes where 7 spans four times more).
constexpr double kGuidedRoom = 0.01;
/// The squares of the shifts' steps relative to the samples' step, 4^-j, largest first.
constexpr std::array<double, kLastShift + 1> shiftFactors() {
  std::array<double, kLastShift + 1> f{};
  double v = 1;
  for (int j = 0; j <= kLastShift; ++j, v /= 4) f[size_t(j)] = v;
  return f;
}
constexpr std::array<double, kLastShift + 1> kShiftFactors = shiftFactors();

/// Rounds a coded interpolant's points (rounded_points.hpp) with the largest step q = step / 2^j
/// whose rounded model stays within the bound and within kRoundingGrowth of c.error (RMSE, or
/// the largest error for a pointwise bound) and whose codes span at most 65,536 steps (a cache
/// keeps it in 1 or 2 bytes a point): j appended to the payload, the rounded model's error kept.
/// Returns false, the candidate as it is, when no shift does.
bool roundInterpolantPoints(const std::vector<float>& s, Int3 n, double bound, BoundKind kind,
                            BlockFitter& fitter, const FitResult& model, Candidate& c) {
  double step = 0;
  std::memcpy(&step, c.bytes.data(), sizeof step);  // the coded samples' step, as a reader reads it
  const double allowed = std::min(
      bound, kRoundingGrowth * (kind == BoundKind::MaxError ? c.error.maxError : c.error.rmse));
  // The thread's buffers, kept between blocks (a block's worth of fresh pages is costly).
  thread_local FitResult rounded;
  rounded.ncp = model.ncp;
  rounded.degree = model.degree;
  bool spanFits = true;
  auto passes = [&](int j, ErrorStats& e) {
    const double q = std::ldexp(step, -j);
    rounded.control = model.control;
    uint64_t span;
    if (!roundPointsSpan(rounded.control.data(), rounded.control.size(), q, span))
      return spanFits = false;
    if (span >= kMaxCompactSpan) return spanFits = false;  // smaller steps span more
    e = errorForBound(fitter, kind, s, n, rounded, nullptr);
    return keeps(kind, e, allowed);
  };
  int best = -1;
  ErrorStats kept, e;
  const double e0 = c.error.rmse, room = allowed * allowed - e0 * e0;
  if (kind == BoundKind::Rmse && room >= kGuidedRoom * e0 * e0) {
    // The measure: what the rounding adds to the squared error, against what the allowance leaves
    // (passing exactly where keeps does).
    const double never = std::numeric_limits<double>::infinity();
    auto added = [&](double factor) {
      const int j = int(std::lround(-std::log2(factor) / 2));
      spanFits = true;
      if (!passes(j, e)) {
        const double m = spanFits ? e.rmse * e.rmse - e0 * e0 : never;
        return std::max(m, std::nextafter(room, never));
      }
      kept = e;
      return std::min(e.rmse * e.rmse - e0 * e0, room);
    };
    int hint = 0;
    while (hint < kLastShift && kRoundingGain * std::pow(std::ldexp(step, -hint), 2) / 12 > room)
      ++hint;
    best = largestPassingGuided(kShiftFactors.data(), kLastShift + 1, hint, room, added);
  } else {
    for (int j = kFirstShift; j >= 0 && passes(j, e); --j) best = j, kept = e;
    for (int j = kFirstShift + 1; best < 0 && spanFits && j <= kLastShift; ++j)
      if (passes(j, e)) best = j, kept = e;
  }
  if (best < 0) return false;
  c.bytes.push_back(uint8_t(best));
  c.error = kept;
  c.roundedPoints = true;
  return true;
}

/// Steps below which integer samples are ladder-searched by the walk (largestPassingStepFrom), not
/// the guided search: at 1e-3 a uint8 scan's step is about 0.9 units, where bucky's integer form
/// passes at factor 1 with an RMSE of 0.2546 of 0.255 and, against the proportion's 0.293, at a
/// larger step too (factor 1.15 is a step of 1.02 units).
constexpr double kLatticeSteps = 4;

/// Whether every sample is an integer (a scan of integer type, converted to float).
bool integerValued(const std::vector<float>& s) {
  for (const float v : s)
    if (v != std::nearbyint(v)) return false;
  return true;
}

/// A form's quantization of the samples at the largest step of its ladder that keeps the bound
/// (ladderSamples), kept for codeLaddered: one a form on each thread, reused (no allocation a
/// block), valid until that form's next ladder.
struct LadderedSamples {
  QuantizedValues kept;
  ErrorStats error;  ///< of the decoded samples
};
LadderedSamples& laddered(Predictor form) {
  thread_local LadderedSamples integer, dbl;
  return isIntegerForm(form) ? integer : dbl;
}

/// The samples quantized in the given form (predicted with interpolation) at the largest step
/// that keeps the bound, into laddered(form); `rung`: the ladder's hint in, its answer out.
bool ladderSamples(const std::vector<float>& s, const uint32_t* valid, int64_t holeSlack, Int3 n,
                   double bound, BoundKind kind, Predictor form, int& rung) {
  const FreeValues free{valid, holeSlack};
  thread_local QuantizedValues trial;  // the step being tried
  LadderedSamples& l = laddered(form);
  bool lattice = true;
  // The measure a bound keeps (keeps): RMSE or the largest error.
  auto measure = [&](double k) {
    if (!quantizeValues(s.data(), n, ladderStep(kind, bound, k), form, trial, free)) {
      lattice = false;
      return std::numeric_limits<double>::infinity();
    }
    const HugePageVector<float>& recon = trial.reconstructed;
    const ErrorStats e = compare([&recon](size_t i) { return recon[i]; }, s, valid);
    if (keeps(kind, e, bound)) {
      l.error = e;
      std::swap(trial, l.kept);
    }
    return kind == BoundKind::MaxError ? e.maxError : e.rmse;
  };
  // Integer samples rounded to a step of a few units are far from proportional (a step near a
  // unit reproduces them): there the walk.
  const bool walk =
      rung >= 0 && ladderStep(kind, bound, kStepFactors[rung]) < kLatticeSteps && integerValued(s);
  const int best = walk
                       ? largestPassingStepFrom(rung, [&](double k) { return measure(k) <= bound; })
                       : largestPassingStepGuided(rung, bound, measure);
  rung = best;
  return best >= 0 && lattice && l.kept.step == ladderStep(kind, bound, kStepFactors[best]);
}

/// The form's laddered samples coded as an Interpolant (at `coding`'s trial level); false where
/// their estimate says they cannot beat `beat` bytes. The decoded model is not yet measured
/// (checkInterpolant).
bool codeLaddered(Predictor form, Int3 n, int degree, EntropyCoding coding, double beat,
                  Candidate& out) {
  LadderedSamples& l = laddered(form);
  // Cannot win (where there is something to beat): spare the coding.
  if (std::isfinite(beat) && estimateQuantizedBytes(l.kept) > beat) return false;
  Candidate c;
  c.kind = BlockKind::Interpolant;
  c.ncp = n;
  for (int a = 0; a < 3; ++a) c.degree[a] = effectiveDegree(degree, n[a]);
  c.frames = encodeQuantized(l.kept, coding, c.bytes);
  c.error = l.error;  // of the decoded samples; the interpolant's own is measured by the check
  c.decoded = &l.kept.reconstructed;
  out = std::move(c);
  return true;
}

/// A trial frame's bytes against the order-0 estimate of the same codes (estimateQuantizedBytes):
/// at least this share of it. Measured 0.992-1.025 for both forms over the 475 interpolants of
/// the corpus and the real-like 602x740x632 scan at 1e-2.
constexpr double kTrialOverEstimate = 0.99;

/// Whether a double form of `dbl` coded bytes wins over the integer form whatever its coding
/// makes of `integerEstimate` (doubleFormWins against the least it codes to): then the integer
/// form is not coded.
bool doubleFormSurelyWins(size_t dbl, double integerEstimate) {
  return double(dbl) < kDoubleFormShare * kTrialOverEstimate * integerEstimate;
}

/// Whether a coded interpolant (codeLaddered) keeps the bound as decoded, measured on the
/// samples (float rounding of the interpolant may break it); its error then in c, and its points
/// rounded where that pays (roundInterpolantPoints).
bool checkInterpolant(const std::vector<float>& s, const uint32_t* valid, Int3 n, double bound,
                      BoundKind kind, BlockFitter& fitter, Candidate& c) {
  ModelEntry probe;
  probe.kind = c.kind;
  probe.coded = true;
  probe.integerCoded = payloadIsIntegerCoded(c.bytes.data(), c.bytes.size());
  probe.lanesCoded = payloadIsLanesCoded(c.bytes.data(), c.bytes.size());
  probe.ncp = c.ncp;
  probe.degree = c.degree;
  probe.size = payloadBytes(n);
  probe.storedSize = c.bytes.size();
  thread_local FitResult model;  // kept between blocks, as its pages
  model.ncp = n;
  model.degree = c.degree;
  model.control.resize(s.size());
  if (c.decoded)  // the samples the bytes decode to, held: their points without decoding them
    interpolantPoints(probe, c.decoded->data(), model.control.data(), "interpolant");
  else
    decodeStoredPayload(probe, c.bytes.data(), model.control.data(), "interpolant");
  c.decoded = nullptr;
  // The error of these bytes' decoding, as the reader decodes them; with rounded points, of
  // their rounding (roundedPoint, as the reader rounds them) to the step the appended shift gives.
  // The points are rounded within kRoundingGrowth of the decoded samples' error (c.error, from the
  // ladder: the interpolant reproduces them at the samples up to float rounding); the interpolant
  // unrounded is measured only where no rounding keeps that.
  if (!valid && roundInterpolantPoints(s, n, bound, kind, fitter, model, c)) {
    c.measuredAsRead = true;
    return true;
  }
  c.error = errorForBound(fitter, kind, s, n, model, valid);
  if (!keeps(kind, c.error, bound))
    return false;  // float rounding of the interpolant: leave it to the others
  c.measuredAsRead = true;
  return true;
}

/// checkInterpolant of the coded forms that keepSmallerForm may keep: where their sizes decide
/// between them whatever rounded-points byte the checks add, the one it prefers first and the
/// other only where that one fails its check (which form is kept, and how, is as with both
/// checked); else both. `has*`: coded and checked, keeping the bound.
void checkBothForms(const std::vector<float>& s, const uint32_t* valid, Int3 n, double bound,
                    BoundKind kind, BlockFitter& fitter, bool codedInteger, Candidate& integer,
                    bool& hasInteger, bool codedDouble, Candidate& dbl, bool& hasDouble) {
  auto check = [&](bool coded, Candidate& c) {
    return coded && checkInterpolant(s, valid, n, bound, kind, fitter, c);
  };
  const size_t di = integer.bytes.size(), dd = dbl.bytes.size(), r = kRoundedPointsBytes;
  const bool sure =
      codedInteger && codedDouble && (doubleFormWins(dd + r, di) || !doubleFormWins(dd, di + r));
  if (sure && doubleFormWins(dd, di)) {
    hasDouble = check(true, dbl);
    hasInteger = !hasDouble && check(true, integer);
  } else if (sure) {
    hasInteger = check(true, integer);
    hasDouble = !hasInteger && check(true, dbl);
  } else {
    hasInteger = check(codedInteger, integer);
    hasDouble = check(codedDouble, dbl);
  }
}

/// How the holes of a block with missing samples are coded (FreeValues::slack), each tried: as
/// filled (hole_fill.hpp), free where their prediction lies within kNearFillSteps of the filling,
/// and free everywhere. Measured on the 44 masked files of Testing/Benchmarks/missing_values.sh:
/// the best of all three is 0.7% smaller in sum than the best of the first and last, and wins where
/// free holes wander (a CT's field of view at max-error 1e-3: 2.4%); neither alone is best on
/// every file.
constexpr int64_t kNearFillSteps = 16;
constexpr int64_t kHoleSlacks[] = {0, kNearFillSteps, FreeValues::kAnySlack};

/// The samples as an Interpolant in whichever form stores them smaller (keepSmallerForm), the
/// holes (if any) coded with `slack`: both forms laddered, the double form coded first, the
/// integer form where its estimate leaves it a chance against the double form's bytes or where
/// the double form fails its check (which form is kept, and how, is as with both coded).
/// `loses`: a payload of that many bytes or more loses to the other candidate; where both forms'
/// coded bytes do, neither is decoded and measured, as whichever the check left would lose
/// (rounded points only add a byte).
bool codeSamplesWithSlack(const std::vector<float>& s, const uint32_t* valid, int64_t slack, Int3 n,
                          int degree, double bound, BoundKind kind, EntropyCoding coding,
                          double beat, size_t loses, BlockFitter& fitter, Candidate& best) {
  constexpr Predictor integerForm = Predictor::IntegerInterpolation;
  constexpr Predictor doubleForm = Predictor::Interpolation;
  // The integer form's rung, then the double form's from it: the likely one.
  int rung = kind == BoundKind::Rmse ? kRoundingRung : -1;
  const bool ladderedInteger = ladderSamples(s, valid, slack, n, bound, kind, integerForm, rung);
  const bool ladderedDouble = ladderSamples(s, valid, slack, n, bound, kind, doubleForm, rung);
  Candidate integer, dbl;
  const bool codedDouble = ladderedDouble && codeLaddered(doubleForm, n, degree, coding, beat, dbl);
  const bool deferInteger =
      ladderedInteger && codedDouble &&
      doubleFormSurelyWins(dbl.bytes.size(), estimateQuantizedBytes(laddered(integerForm).kept));
  const bool codedInteger = ladderedInteger && !deferInteger &&
                            codeLaddered(integerForm, n, degree, coding, beat, integer);
  if (!(codedInteger && integer.bytes.size() < loses) && !(codedDouble && dbl.bytes.size() < loses))
    return false;
  bool hasInteger = false, hasDouble = false;
  checkBothForms(s, valid, n, bound, kind, fitter, codedInteger, integer, hasInteger, codedDouble,
                 dbl, hasDouble);
  if (deferInteger && !hasDouble)  // as checkBothForms would have gone on with both coded
    hasInteger = codeLaddered(integerForm, n, degree, coding, beat, integer) &&
                 checkInterpolant(s, valid, n, bound, kind, fitter, integer);
  return keepSmallerForm(hasInteger, integer, hasDouble, dbl, best);
}

/// The samples as an Interpolant (codeSamplesWithSlack); with missing samples, with each way of
/// coding the holes (kHoleSlacks), whichever is smallest (the quantization step the ladder
/// reaches differs between them).
bool codeSamples(const std::vector<float>& s, const uint32_t* valid, Int3 n, int degree,
                 double bound, BoundKind kind, EntropyCoding coding, double beat, size_t loses,
                 BlockFitter& fitter, Candidate& out) {
  if (!(bound > 0)) return false;
  bool found = false;
  for (const int64_t slack : kHoleSlacks) {
    if (slack > 0 && !valid) break;
    Candidate best;
    if (!codeSamplesWithSlack(s, valid, slack, n, degree, bound, kind, coding, beat, loses, fitter,
                              best))
      continue;
    if (!found || best.bytes.size() < out.bytes.size()) out = std::move(best);
    found = true;
  }
  return found;
}

void storeCandidate(Candidate& c, BlockTask& t) {
  ModelEntry& m = t.entry;
  m.kind = c.kind;
  m.coded = c.kind != BlockKind::Constant;
  m.integerCoded = m.coded && payloadIsIntegerCoded(c.bytes.data(), c.bytes.size());
  m.lanesCoded = m.coded && payloadIsLanesCoded(c.bytes.data(), c.bytes.size());
  m.roundedPoints = c.roundedPoints;
  m.ncp = c.ncp;
  m.degree = c.degree;
  setError(t, c.error);
  t.measuredAsRead = c.measuredAsRead;
  t.stored = std::move(c.bytes);
  m.storedSize = t.stored.size();
}

/// Bits a value of a trial frame from which an RMSE bound's large payload keeps it (denseFrame).
constexpr double kDenseFrameBits = 3;

/// Whether a candidate's trial frame (`frameBytes`, coding `values` values) is kept as it is, not
/// coded again at the file's level: under an RMSE bound, kLanesSureValues values or more at
/// kDenseFrameBits bits a value or more (the codes of a noisy block's points or samples, where
/// zstd's slow level finds few repeats to gain on its fast one). Measured at 1 thread against
/// coding them again: the head MRI made 301x370x316 (--noise 2.5 --detail 18) at 1e-2 2.18 ->
/// 1.73 user s for 40 bytes more (+0.002%), the corpus and the head made 150x194x132 at 1e-3
/// 1.61 -> 0.98 s for +0.13%, the corpus at 1e-2 the same bytes. Not for pointwise bounds (+4.3%
/// on the corpus at max error 1e-3), nor at fewer bits (all large payloads: +7.6% on the corpus at
/// 1e-2, whose smooth blocks' codes repeat).
bool denseFrame(BoundKind kind, size_t frameBytes, size_t values) {
  return kind == BoundKind::Rmse && values >= kLanesSureValues &&
         double(frameBytes) * 8 >= kDenseFrameBits * double(values);
}

/// The kept candidate's entropy frame coded at the file's level (codeAtFileLevel).
void finalFrame(const FitContext& c, Candidate& best) {
  if (best.kind == BlockKind::Constant) return;
  const size_t tail = best.roundedPoints ? kRoundedPointsBytes : 0;
  const size_t values = size_t(best.ncp[0]) * size_t(best.ncp[1]) * size_t(best.ncp[2]);
  // Coded again, the frame holds the same symbols (recodeFrame checks): a measured interpolant's
  // error stays the error of what a reader decodes.
  codeAtFileLevel(c.opt, best.bytes, tail, values, best.frames);
}

/// A block whose spline needs more than kNoiseShare of its samples per axis to meet the bound
/// (noise above the bound: a real scan's detail) ends as its coded samples, whose bytes a spline
/// of nearly as many points, quantized within what its fit leaves of the bound, does not beat.
/// One fit at that NCP on every axis tells, instead of the search's ten and the spline's coding.
/// At 0.9 a spline of 0.85-0.9 of the samples per axis (0.61-0.73 of their count) was searched and
/// kept where it spent under a bit a sample, though the samples coded smaller (ironProt at 1e-2:
/// 30,509 against 15,771 bytes), and a Gray-Scott step made 512^3 with noise at 1.8 bounds was
/// searched in nine fits a block to end as samples (the same bytes at 0.85, 1.8x faster).
constexpr double kNoiseShare = 0.85;
constexpr int kNoiseMinSamples = 16;  ///< smaller blocks: the search is cheap, and decides

/// Whether the probe may apply at all (before the samples' roughness is known): a searched block of
/// at least kNoiseMinSamples along some axis, with no missing samples.
bool mayProbeForNoise(const BlockExtent& e, const BlockTask& t) {
  const int nmax = std::max({e.samples[0], e.samples[1], e.samples[2]});
  return t.search && nmax >= kNoiseMinSamples && t.mask.empty();
}

}  // namespace

std::optional<Int3> noiseProbeNcp(const FitContext& c, const BlockExtent& e, const BlockTask& t,
                                  const std::array<double, 3>& rough) {
  if (!mayProbeForNoise(e, t)) return std::nullopt;
  // The probe only where the samples' second differences say noise of half the bound or more
  // (white noise of deviation s has a mean squared second difference of 6 s^2 along every axis):
  // elsewhere it would be one fit more.
  // And only where every axis is about as rough as the roughest (refineNcpPerAxis would give none
  // fewer points): a block smooth along some axis may be a spline of few points there.
  double smoothest = std::numeric_limits<double>::infinity(), roughest = 0;
  for (int a = 0; a < 3; ++a)
    if (e.samples[a] >= 3) {
      smoothest = std::min(smoothest, rough[size_t(a)]);
      roughest = std::max(roughest, rough[size_t(a)]);
    }
  if (!(smoothest / 6 >= 0.25 * c.bound * c.bound) || !(smoothest * kAnisotropy > roughest))
    return std::nullopt;
  Int3 ncp{};  // kNoiseShare of each axis's samples
  for (int a = 0; a < 3; ++a)
    ncp[a] = std::max(effectiveDegree(c.opt.degree, e.samples[a]) + 1,
                      std::min(e.samples[a], int(std::ceil(kNoiseShare * e.samples[a]))));
  return ncp;
}

namespace {

/// Whether the block is noise-dominated in that sense (noiseProbeNcp's probe misses the fit's
/// share of the bound: its verdict given ahead, else a fit); then t's search statistics say so.
bool noiseDominated(const FitContext& c, const BlockExtent& e, BlockFitter& fitter, BlockTask& t) {
  if (!mayProbeForNoise(e, t)) return false;
  if (!t.roughness) t.roughness = axisRoughness(t.samples.data(), e.samples, c.smallIntegers);
  const std::optional<Int3> ncp = noiseProbeNcp(c, e, t, *t.roughness);
  if (!ncp) return false;
  const double bound = searchBound(c.opt, c.bound);
  const Verdict v = t.verdicts.at(*ncp, bound);
  thread_local FitResult probe;
  if (v == Verdict::Unknown) ++t.fits;
  if (v == Verdict::Unknown
          ? fitter.fitWithin(t.samples.data(), e.samples, *ncp, c.opt.degree, bound,
                             sumOfSquares(t.samples.data(), e.samples), probe)
          : v == Verdict::Passes)
    return false;
  t.ncpStar = std::max({e.samples[0], e.samples[1], e.samples[2]});
  t.complex = true;
  return true;
}

/// Compact storage: a constant where one meets the bound; else the smaller of the coded spline
/// (fitted to kFitShare of the bound) and the coded samples; the float samples where neither does.
void encodeCompact(const FitContext& c, const BlockExtent& e, BlockFitter& fitter, BlockTask& t) {
  Candidate best, other;
  const BoundKind kind = c.opt.boundKind;
  if (constantFits(e, t.samples, validOf(t), c.opt.degree, c.bound, kind, best)) {
    t.complex = false;
    storeCandidate(best, t);
    return;
  }
  if (noiseDominated(c, e, fitter, t) &&
      codeSamples(t.samples, validOf(t), e.samples, c.opt.degree, c.bound, kind, trialCoding(c.opt),
                  std::numeric_limits<double>::infinity(), SIZE_MAX, fitter, best)) {
    finalFrame(c, best);
    storeCandidate(best, t);
    return;
  }
  FitResult fr;
  fitBlock(c, e, fitter, searchBound(c.opt, c.bound), t, fr);
  const int64_t count = int64_t(t.samples.size());
  const bool haveSpline =
      !t.exact && int64_t(fr.ncp[0]) * fr.ncp[1] * fr.ncp[2] < count &&
      codeSpline(fr, t.samples, e.samples, c.bound, kind, trialCoding(c.opt), fitter, best);
  // Samples pay when the spline is missing or spends more than a bit per sample (masked blocks,
  // whose fitted splines also follow the filled holes, always try them); they are coded only when
  // their estimated size (order-0 entropy of the codes, which zstd roughly reaches) could beat it.
  const double beat =
      haveSpline ? 1.2 * double(best.bytes.size()) : std::numeric_limits<double>::infinity();
  if ((!haveSpline || int64_t(best.bytes.size()) * 8 > count || !t.mask.empty()) &&
      codeSamples(t.samples, validOf(t), e.samples, c.opt.degree, c.bound, kind, trialCoding(c.opt),
                  beat, haveSpline ? best.bytes.size() : SIZE_MAX, fitter, other) &&
      (!haveSpline || other.bytes.size() < best.bytes.size())) {
    best = std::move(other);
    t.complex = true;
  } else if (!haveSpline) {
    exactModel(e, t, fr);
    t.exact = true;
    t.complex = true;
    storeFloat(fr, true, t);
    return;
  }
  finalFrame(c, best);
  storeCandidate(best, t);
}

}  // namespace

void codeAtFileLevel(const EncoderOptions& opt, std::vector<uint8_t>& payload, size_t tail,
                     size_t values, FrameSizes trial) {
  if (opt.entropy == EntropyStage::Lanes) return;
  const size_t head = codedHeaderBytes(payload.data(), payload.size());
  const size_t frameBytes = payload.size() - head - tail;
  if (opt.entropy == EntropyStage::Auto && lanesFrameSure(trial, frameBytes, values)) return;
  if (denseFrame(opt.boundKind, frameBytes, values)) return;
  recodeFrame(payload, head, tail, values, entropyCoding(opt), trial);
}

double searchBound(const EncoderOptions& opt, double bound) {
  return opt.compact && bounded(opt.mode) ? kFitShare * bound : bound;
}

ErrorStats errorAsDecoded(const ModelEntry& m, const float* points, const BlockTask& t) {
  thread_local std::vector<float> values;
  decodeBlockSamples(m, points, EncodingMode::Adaptive, values);
  if (values.size() != t.samples.size())
    throw FormatError("a decoded block has " + std::to_string(values.size()) + " samples, not " +
                      std::to_string(t.samples.size()));
  return errorOnValid(values.data(), t.samples.data(), values.size(),
                      t.mask.empty() ? nullptr : t.mask.data());
}

void setError(BlockTask& t, const ErrorStats& es) {
  ModelEntry& m = t.entry;
  t.rmse = es.rmse;
  t.maxError = es.maxError;
  m.minValue = float(es.minValue);
  m.maxValue = float(es.maxValue);
  m.rmse = float(es.rmse);
  m.maxError = float(es.maxError);
}

void storeDownsampled(const BlockExtent& e, BlockTask& t) {
  ModelEntry& m = t.entry;
  for (int a = 0; a < 3; ++a) {
    m.ncp[a] = e.samples[a] + 2;
    m.degree[a] = 1;
  }
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  const int gx = m.ncp[0], gy = m.ncp[1];
  for (int z = 1; z <= e.samples[2]; ++z)
    for (int y = 1; y <= e.samples[1]; ++y)
      for (int x = 1; x <= e.samples[0]; ++x) {
        const float v = t.samples[(size_t(z) * size_t(gy) + size_t(y)) * size_t(gx) + size_t(x)];
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
  m.minValue = lo;
  m.maxValue = hi;
  m.kind = BlockKind::Spline;
  t.stored = bytesOf(t.samples);
  m.storedSize = t.stored.size();
}

namespace {

/// A run's block whose model at the step before still meets the bound on its samples (`moved`,
/// the model's error on them): stored as a reference to it (no payload).
void referPrevious(const ModelEntry& previous, const ErrorStats& moved, BlockTask& t) {
  ModelEntry& m = t.entry;
  m.kind = previous.kind;
  m.coded = previous.coded;
  m.integerCoded = previous.integerCoded;
  m.lanesCoded = previous.lanesCoded;
  m.roundedPoints = previous.roundedPoints;
  m.ncp = previous.ncp;
  m.degree = previous.degree;
  m.reference = true;
  setError(t, moved);
  t.stored.clear();
  m.storedSize = 0;
}

}  // namespace

namespace {

/// A block without a valid sample: no payload.
void storeEmpty(const FitContext& c, const BlockExtent& e, BlockTask& t) {
  ModelEntry& m = t.entry;
  m.kind = BlockKind::Empty;
  m.coded = m.integerCoded = m.lanesCoded = m.masked = m.roundedPoints = false;
  for (int a = 0; a < 3; ++a) {
    m.degree[a] = effectiveDegree(c.opt.degree, e.samples[a]);
    m.ncp[a] = m.degree[a] + 1;
  }
  setError(t, ErrorStats{});
  t.stored.clear();
  m.storedSize = 0;
}

/// A block with missing samples: their mask in t.mask and its holes filled. false when no sample
/// is valid (the block is then stored empty).
bool prepareMissing(const FitContext& c, const BlockExtent& e, BlockTask& t) {
  t.mask = maskOfValid(t.samples.data(), int64_t(t.samples.size()));
  const int64_t valid = validCount(t.mask);
  if (valid == 0) {
    storeEmpty(c, e, t);
    return false;
  }
  if (valid == int64_t(t.samples.size())) {
    t.mask.clear();
  } else {
    fillMissing(t.samples.data(), e.samples, t.mask);
  }
  return true;
}

/// A masked block's payload: the coded mask section before the model's own (block_mask.hpp).
void prependMask(const BlockExtent& e, BlockTask& t) {
  const std::vector<uint8_t> coded = encodeMask(t.mask, e.samples);
  std::vector<uint8_t> stored(maskSectionBytes(coded.size()), 0);
  const uint32_t length = uint32_t(coded.size());
  std::memcpy(stored.data(), &length, 4);
  std::memcpy(stored.data() + 4, coded.data(), coded.size());
  stored.insert(stored.end(), t.stored.begin(), t.stored.end());
  t.stored = std::move(stored);
  t.entry.masked = true;
  t.entry.storedSize = t.stored.size();
}

/// The fitter judges models on t's valid samples while it lives (BlockFitter::setMask).
struct MaskScope {
  BlockFitter& fitter;
  MaskScope(BlockFitter& f, const BlockTask& t) : fitter(f) {
    fitter.setMask(t.mask.empty() ? nullptr : &t.mask);
  }
  ~MaskScope() { fitter.setMask(nullptr); }
  MaskScope(const MaskScope&) = delete;
  MaskScope& operator=(const MaskScope&) = delete;
};

}  // namespace

namespace {

/// The stored block as a reader decodes it: its final payload, with its flags and mask section,
/// through decodeStoredPayload (what AfamFile's readers call), measured by errorAsDecoded. A
/// reference has no payload and a residual is measured on its decoding when chosen.
ErrorStats errorAsRead(const FitContext& c, const BlockTask& t) {
  ModelEntry m = t.entry;
  m.size = decodedBytes(m);
  thread_local std::vector<float> points;
  points.resize(m.size / sizeof(float));
  decodeStoredPayload(m, t.stored.data(), points.data(),
                      c.sourceName + ": " + Partition::blockName(c.level, t.ijk));
  return errorAsDecoded(m, points.data(), t);
}

/// The step before's model (`previous`) measured on this step's samples as a reader decodes it
/// (errorAsDecoded, on the values the step before keeps): the error of the block if it refers to
/// that model. Blocks with missing samples are not coded in time.
ErrorStats movedError(const FitContext& c, const ModelEntry& previous, const BlockExtent& e,
                      const BlockTask& t) {
  ModelEntry m = previous;
  m.samples = e.samples;
  ErrorStats es;
  c.opt.previous->values(c.level, t.ijk, m, [&](const float* values, size_t count) {
    if (count != t.samples.size())
      throw FormatError("the step before's model has " + std::to_string(count) + " samples, not " +
                        std::to_string(t.samples.size()));
    es = errorOnValid(values, t.samples.data(), count, nullptr);
  });
  return es;
}

/// Checks the stored block through the reader's decoding (errorAsRead) and keeps that error in
/// the index; a block that does not decode or that the reader would see over the bound is stored
/// as its float samples (the exact model), and if even that fails the encode stops naming it.
void checkAsRead(const FitContext& c, const BlockExtent& e, BlockTask& t) {
  if (!bounded(c.opt.mode) || t.entry.reference || t.entry.residual ||
      t.entry.kind == BlockKind::Empty || (t.measuredAsRead && t.mask.empty()))
    return;
  ErrorStats es;
  bool decodes = true;
  try {
    es = errorAsRead(c, t);
  } catch (const FormatError&) {
    decodes = false;  // the exact form below, or the encode stops
  }
  if ((!decodes || !keeps(c.opt.boundKind, es, c.bound)) && t.entry.kind != BlockKind::Samples) {
    FitResult fr;
    exactModel(e, t, fr);
    t.exact = t.complex = true;
    const bool masked = t.entry.masked;
    t.entry.masked = false;
    storeFloat(fr, true, t);
    if (masked) prependMask(e, t);
    es = errorAsRead(c, t);
  }
  setError(t, es);
}

/// A run's first step: whether the block is coded with runCodedShare's headroom
/// (EncoderOptions::firstStepHeadroom).
bool firstStepHeadroom(const FitContext& c, Int3 ijk) {
  return c.opt.runStep && !c.opt.previous && c.opt.firstStepHeadroom &&
         c.opt.firstStepHeadroom(c.level, ijk);
}

void encodeBlockAnew(const FitContext& c, const BlockExtent& e, BlockFitter& fitter, BlockTask& t) {
  try {
    if (c.mayMiss && anyNaN(t.samples.data(), t.samples.size()) && !prepareMissing(c, e, t)) return;
    const MaskScope scope(fitter, t);
    // A run's step: the block's model at the step before, and how far the block moved from it.
    // Masked blocks are coded on their own (their models are never shared in time).
    ModelEntry previous;
    bool mayRefer = false;
    const bool before = c.opt.previous && bounded(c.opt.mode) && t.mask.empty() &&
                        c.opt.previous->entry(c.level, t.ijk, previous, mayRefer);
    const bool inTime = before && mayRefer;
    const ErrorStats moved = inTime ? movedError(c, previous, e, t) : ErrorStats{};
    // A run's coded blocks leave part of the bound to the steps after (runCodedShare) where the
    // block moved little since the step before, and at a key step (the model the next steps
    // refer to); at the first step, where the caller found that it pays (firstStepHeadroom).
    const bool headroom =
        firstStepHeadroom(c, t.ijk) ||
        (c.opt.runStep && before && (!mayRefer || moved.rmse <= kDriftForHeadroom * c.bound));
    FitContext coded = c;
    if (headroom) coded.bound = c.bound * c.opt.runCodedShare;
    if (inTime && keeps(c.opt.boundKind, moved, c.bound)) {
      referPrevious(previous, moved, t);  // the step before's model, unchanged
    } else if (c.opt.compact && bounded(c.opt.mode)) {
      encodeCompact(coded, e, fitter, t);
      if (inTime) {
        FitResult model;  // the step before's control points, which the residual codes against
        c.opt.previous->control(c.level, t.ijk, previous, model);
        codeResidualIfSmaller(coded, e, fitter, previous, model, t);
      }
    } else {
      FitResult fr;
      fitBlock(c, e, fitter, searchBound(c.opt, c.bound), t, fr);
      storeFloat(fr, t.exact, t);
    }
    if (!t.mask.empty()) prependMask(e, t);
    checkAsRead(c, e, t);
  } catch (const NumericError& ex) {
    throw NumericError("encode: " + Partition::blockName(c.level, t.ijk) + " of " + c.sourceName +
                       ": " + ex.what());
  } catch (const FormatError& ex) {
    throw NumericError("encode: " + Partition::blockName(c.level, t.ijk) + " of " + c.sourceName +
                       " does not decode as written: " + ex.what());
  }
  if (bounded(c.opt.mode) &&
      !keeps(c.opt.boundKind, ErrorStats{t.rmse, t.maxError, 0, 0}, c.bound)) {
    const bool pointwise = c.opt.boundKind == BoundKind::MaxError;
    std::ostringstream msg;
    msg << "encode: " << Partition::blockName(c.level, t.ijk) << " of " << c.sourceName << " has "
        << (pointwise ? "a sample off by " : "RMSE ") << (pointwise ? t.maxError : t.rmse)
        << ", over the bound " << c.bound << " as a reader decodes it, even stored exactly";
    throw NumericError(msg.str());
  }
  for (int a = 0; a < 3; ++a)
    if (e.samples[a] > 1 && e.samples[a] <= c.opt.degree) t.reducedDegree = true;
}

}  // namespace

void encodeBlock(const FitContext& c, const BlockExtent& e, BlockFitter& fitter, BlockTask& t) {
  // A run's first step encoded again (FirstStepBlocks): a block of the same samples, bound and
  // search is the same model, taken instead of fitted.
  FirstStepBlocks* const memo =
      c.opt.runStep && !c.opt.previous ? c.opt.firstStepBlocks.get() : nullptr;
  if (!memo) return encodeBlockAnew(c, e, fitter, t);
  const double bound = firstStepHeadroom(c, t.ijk) ? c.bound * c.opt.runCodedShare : c.bound;
  if (memo->take(c.level, bound, t)) return;
  encodeBlockAnew(c, e, fitter, t);
  memo->keep(c.level, bound, t);
}

}  // namespace afam
