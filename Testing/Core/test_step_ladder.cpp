// SPDX-License-Identifier: BSD-3-Clause
// The encoder's step ladder searches (afam/encode/step_ladder.hpp): the guided search finds the
// walk's rung in fewer measures where the measure is near proportional to the step, and the walk
// and bisection agree on monotone tests.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "afam/encode/step_ladder.hpp"

namespace afam {
namespace {

constexpr int kRungs = int(sizeof(kStepFactors) / sizeof(kStepFactors[0]));

/// A ladder test that counts its measures and remembers the factor of the last one that passed.
struct Counted {
  double limit;
  double (*shape)(double factor, double scale);
  double scale;
  int measures = 0;
  double lastPassed = -1;
  double operator()(double f) {
    ++measures;
    const double m = shape(f, scale);
    if (m <= limit) lastPassed = f;
    return m;
  }
};

double proportional(double f, double scale) { return scale * f; }
/// Below proportion by up to 4% at the larger steps (as integer samples' RMSE grows at 1e-2).
double sublinear(double f, double scale) { return scale * f * (1.0 - 0.02 * std::log2(f + 1.0)); }

TEST(StepLadder, TheGuidedSearchFindsTheWalksRungInAtMostThreeMeasuresWhenProportional) {
  // Every hint, and limits placing the answer anywhere on the ladder (and off both ends): the
  // walk's answer, the last passing measure the answer's, and at most three measures (the one
  // predicted, and a neighbour predicted within the margin) where the walk took up to the
  // ladder's length.
  int walkMeasures = 0, guidedMeasures = 0;
  for (int hint = 0; hint < kRungs; ++hint)
    for (double limit = 0.2; limit < 5.0; limit *= 1.037) {
      Counted walk{limit, proportional, 1.0}, guided{limit, proportional, 1.0};
      const int expected = largestPassingStepFrom(hint, [&](double f) { return walk(f) <= limit; });
      const int got = largestPassingStepGuided(hint, limit, guided);
      SCOPED_TRACE("hint " + std::to_string(hint) + " limit " + std::to_string(limit));
      ASSERT_EQ(got, expected);
      if (got >= 0) {
        EXPECT_EQ(guided.lastPassed, kStepFactors[got]);
      }
      EXPECT_LE(guided.measures, 3 + (expected < 0 ? kRungs : 0));
      walkMeasures += walk.measures;
      guidedMeasures += guided.measures;
    }
  EXPECT_LT(guidedMeasures, walkMeasures * 2 / 3);
}

TEST(StepLadder, TheGuidedSearchKeepsTheWalksRungForAMeasureAFewPercentOffProportion) {
  for (int hint = 0; hint < kRungs; ++hint)
    for (double limit = 0.25; limit < 4.0; limit *= 1.011) {
      Counted walk{limit, sublinear, 1.0}, guided{limit, sublinear, 1.0};
      const int expected = largestPassingStepFrom(hint, [&](double f) { return walk(f) <= limit; });
      ASSERT_EQ(largestPassingStepGuided(hint, limit, guided), expected)
          << "hint " << hint << " limit " << limit;
    }
}

TEST(StepLadder, AStepThatCannotBeUsedIsWalkedPast) {
  // Steps from factor 2.6 up cannot be used (infinite measure): the hint's proportion is unknown
  // there, so the search walks to smaller steps and still finds the largest passing one.
  auto measure = [](double f) {
    return f >= 2.6 ? std::numeric_limits<double>::infinity() : 0.5 * f;
  };
  EXPECT_EQ(kStepFactors[largestPassingStepGuided(0, 1.0, measure)], 1.7);  // 0.85 <= 1
  EXPECT_EQ(kStepFactors[largestPassingStepGuided(7, 1.0, measure)], 1.7);
  EXPECT_EQ(largestPassingStepGuided(3, 0.1, measure), -1);  // even the smallest, 0.15, fails
  EXPECT_EQ(largestPassingStepGuided(3, 100.0, [](double f) { return f; }), 0);
}

TEST(StepLadder, WithoutAHintTheGuidedSearchIsTheBisection) {
  for (double limit = 0.2; limit < 5.0; limit *= 1.1) {
    Counted a{limit, proportional, 1.0}, b{limit, proportional, 1.0};
    EXPECT_EQ(largestPassingStepGuided(-1, limit, a),
              largestPassingStep([&](double f) { return b(f) <= limit; }));
    EXPECT_EQ(a.measures, b.measures);
  }
}

TEST(StepLadder, LadderStepsSpendTheBudgetAtFactorOne) {
  // Uniform rounding to step s has RMSE s / sqrt(12) and largest error s / 2.
  EXPECT_NEAR(ladderStep(BoundKind::Rmse, 0.5, 1.0) / std::sqrt(12.0), 0.5, 1e-15);
  EXPECT_DOUBLE_EQ(ladderStep(BoundKind::MaxError, 0.5, 1.0) / 2.0, 0.5);
  EXPECT_DOUBLE_EQ(ladderStep(BoundKind::Rmse, 0.5, 2.1),
                   2.1 * ladderStep(BoundKind::Rmse, 0.5, 1));
}

}  // namespace
}  // namespace afam
