// SPDX-License-Identifier: BSD-3-Clause
// The encoder's quantization step ladder: the steps a coded payload may take, as factors of the
// step whose rounding alone would spend a block's error budget, and the searches for the largest
// step whose test passes (the error grows with the step). Pure logic, tested on its own.
#pragma once

#include <cmath>

#include "afam/format/afam_file.hpp"

namespace afam {

// Quantization steps of coded payloads, as factors of 2 sqrt(3) x the error budget (the step whose
// uniform rounding error alone would spend it), tried from the largest: a larger step is fewer
// bits, and a block whose error budget is not spent gains nothing from it.
constexpr double kStepFactors[] = {4.0, 3.2,  2.6, 2.1,  1.7, 1.4, 1.15,
                                   1.0, 0.85, 0.7, 0.55, 0.4, 0.3};
/// Where a ladder for an RMSE bound starts (largestPassingStepFrom's hint) when no other form of
/// the same values has answered: the samples' at factor 1, where uniform rounding alone spends the
/// budget (an RMSE of step / sqrt(12)), so their ladder ends there or next to it; a
/// spline's at factor 2.1, where 130 of the 203 coded splines of the corpus and the head MRI made
/// 301x370x316 (--detail 18) ended at RMSE 1e-2 (the basis averages the points' rounding; 64 more
/// ended at the next two rungs). Two evaluations where the answer is the hint or a neighbour,
/// instead of the bisection's four or five; the same answer for a monotone test. Pointwise bounds
/// keep the bisection: on integer samples their tests are far from monotone (a step that divides
/// the samples' spacing reproduces them), and hints there made the corpus's files 8% larger.
constexpr int kRoundingRung = 7;
constexpr int kLikelySplineRung = 3;
static_assert(kStepFactors[kRoundingRung] == 1.0, "the rounding rung is factor 1");

/// The quantization step of ladder factor k for an error budget: factors of the step whose
/// rounding alone would spend the budget, 2 sqrt(3) x budget for an RMSE (uniform rounding's RMSE
/// is step / sqrt(12)), 2 x budget for a pointwise bound (its worst case is step / 2).
inline double ladderStep(BoundKind kind, double budget, double k) {
  return (kind == BoundKind::MaxError ? 2.0 : 2.0 * std::sqrt(3.0)) * budget * k;
}

/// The largest factor of kStepFactors (sorted descending) for which passes(factor) holds, by
/// bisection over the ladder (the error grows with the step); -1 when even the smallest fails. The
/// largest is tried first (a block that passes there costs one evaluation); the last call that
/// returned true is the answer's.
template <typename Passes>
int largestPassingStep(Passes&& passes) {
  const int n = int(sizeof(kStepFactors) / sizeof(kStepFactors[0]));
  if (passes(kStepFactors[0])) return 0;
  int fail = 0, pass = n;  // kStepFactors[fail] fails; [pass] passes (n: none known to)
  while (pass - fail > 1) {
    const int mid = (pass + fail) / 2;
    if (passes(kStepFactors[mid]))
      pass = mid;
    else
      fail = mid;
  }
  return pass < n ? pass : -1;
}

/// largestPassingStep when a likely answer is known (the rung another form of the same values
/// chose: their errors are those of a uniform rounding at the same step): that rung and its
/// neighbours towards the answer, usually two evaluations; the same answer as the bisection for
/// a monotone test. hint < 0: the bisection.
template <typename Passes>
int largestPassingStepFrom(int hint, Passes&& passes) {
  const int n = int(sizeof(kStepFactors) / sizeof(kStepFactors[0]));
  if (hint < 0 || hint >= n) return largestPassingStep(passes);
  if (passes(kStepFactors[hint])) {
    int j = hint - 1;
    while (j >= 0 && passes(kStepFactors[j])) --j;
    return j + 1;
  }
  int j = hint + 1;
  while (j < n && !passes(kStepFactors[j])) ++j;
  return j < n ? j : -1;
}

/// How far over the limit a rung's measure, scaled from the last rung measured, may be predicted
/// and the rung still be measured (largestPassingStepGuided).
constexpr double kGuidedMargin = 1.05;

/// The largest of `factors` (n of them, descending) whose measure passes (measure(factor) <=
/// limit), for a measure that grows about in proportion to the factor, starting at factors[hint]
/// (0 <= hint < n): the factor measured next is the largest whose measure, scaled from the last one
/// measured, keeps the limit within kGuidedMargin, between the largest factor known to fail and
/// the smallest known to pass; the search stops where no factor between them is predicted to.
/// The walk's answer (largestPassingStepFrom) wherever the measure is that close to proportional
/// from one factor to the next. The last call that passed is the answer's; -1 when none passes.
/// A measure that is not finite and positive (a factor that cannot be used) says nothing of the
/// next: the search then walks towards the smaller factors.
template <typename Measure>
int largestPassingGuided(const double* factors, int n, int hint, double limit, Measure&& measure,
                         double margin = kGuidedMargin) {
  int fail = -1, pass = n;  // [fail] fails, [pass] passes (-1, n: none known)
  int last = hint;
  double lastMeasure = measure(factors[hint]);
  (lastMeasure <= limit ? pass : fail) = hint;
  while (pass - fail > 1) {
    const bool proportional = lastMeasure > 0 && std::isfinite(lastMeasure);
    int next = -1;
    for (int r = fail + 1; r < pass && next < 0; ++r)
      if (!proportional || lastMeasure * factors[r] / factors[last] <= margin * limit) next = r;
    if (next < 0) {
      if (pass < n) break;  // every factor between is predicted to fail: the smallest passing
      next = fail + 1;      // none passes yet: walk towards the smaller factors
    }
    last = next;
    lastMeasure = measure(factors[next]);
    (lastMeasure <= limit ? pass : fail) = next;
  }
  return pass < n ? pass : -1;
}

/// largestPassingStepFrom for a measure that grows about in proportion to the step, the RMSE of
/// samples rounded to it: step / sqrt(12) for noise, less on smooth or integer samples, and from
/// one rung to the next proportional within a few percent (the corpus's integer forms at 1e-2:
/// 1.41, 1.61, 1.98, 2.28, 2.81 at factors 1, 1.15, 1.4, 1.7, 2.1): largestPassingGuided over the
/// ladder from the hint, in two or three evaluations where the walk from factor 1 took up to
/// five. `measure(factor)`: the test's measure, passing where it is <= limit (infinity where the
/// step cannot be used). hint < 0: the bisection.
template <typename Measure>
int largestPassingStepGuided(int hint, double limit, Measure&& measure,
                             double margin = kGuidedMargin) {
  const int n = int(sizeof(kStepFactors) / sizeof(kStepFactors[0]));
  if (hint < 0 || hint >= n)
    return largestPassingStep([&](double f) { return measure(f) <= limit; });
  return largestPassingGuided(kStepFactors, n, hint, limit, measure, margin);
}

}  // namespace afam
