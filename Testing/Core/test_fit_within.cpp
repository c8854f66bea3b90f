// SPDX-License-Identifier: BSD-3-Clause
// BlockFitter::fitWithin: the same answer as measuring the error, the same model as fitInto, and
// most answers without measuring (the least-squares residual bounds the RMSE tightly).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "afam/spline/fit.hpp"
#include "afam/volume/marschner_lobb.hpp"

using namespace afam;

namespace {

/// Marschner-Lobb on an n0 x n1 x n2 grid, planes z0.. of a grid 4 n2 deep, plus an offset.
std::vector<float> mlBlock(const Int3& n, int z0, float offset) {
  std::vector<float> out(static_cast<size_t>(n[0]) * static_cast<size_t>(n[1]) *
                         static_cast<size_t>(n[2]));
  marschnerLobbSlab(MarschnerLobb{}, {n[0], n[1], 4 * n[2]}, z0, n[2], out.data());
  for (float& v : out) v += offset;
  return out;
}

struct Case {
  const char* name;
  Int3 n;
  std::vector<float> samples;
};

std::vector<Case> cases() {
  std::vector<Case> out;
  out.push_back({"ml 17^3", {17, 17, 17}, mlBlock({17, 17, 17}, 5, 0.0f)});
  out.push_back({"ml 33x17x9 + 1000", {33, 17, 9}, mlBlock({33, 17, 9}, 0, 1000.0f)});
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  std::vector<float> r(13 * 13 * 13);
  for (float& v : r) v = noise(rng);
  out.push_back({"noise 13^3", {13, 13, 13}, r});
  return out;
}

}  // namespace

TEST(FitWithin, AgreesWithTheMeasuredErrorAndMostlyWithoutMeasuring) {
  BlockFitter fitter;
  int decided = 0, calls = 0;
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    const double squares = sumOfSquares(c.samples.data(), c.n);
    for (int k = 3; k <= c.n[0]; k += 2) {
      const Int3 ncp = clampNcp(k, c.n, {2, 2, 2});
      const FitResult ref = fitter.fit(c.samples.data(), c.n, ncp, 2);
      const double rmse = ref.error.rmse;
      ASSERT_GT(rmse, 0.0);
      for (double factor : {0.5, 0.99, 1.0, 1.01, 2.0}) {
        const double bound = factor == 1.0 ? rmse : rmse * factor;
        FitResult out;
        const bool ok = fitter.fitWithin(c.samples.data(), c.n, ncp, 2, bound, squares, out);
        ++calls;
        EXPECT_EQ(ok, rmse <= bound) << "k " << k << " factor " << factor;
        EXPECT_EQ(out.control, ref.control);
        if (!out.errorMeasured) {
          ++decided;
          EXPECT_EQ(out.error.rmse > bound, !ok);  // the decisive end of the range
          if (ok) {
            EXPECT_GE(out.error.rmse, rmse);
          } else {
            EXPECT_LE(out.error.rmse, rmse);
          }
        }
        // Just below the measured RMSE the answer flips, however it is reached.
        EXPECT_FALSE(fitter.fitWithin(c.samples.data(), c.n, ncp, 2, std::nextafter(rmse, 0.0),
                                      squares, out));
        fitter.measure(c.samples.data(), c.n, out);
        EXPECT_TRUE(out.errorMeasured);
        EXPECT_EQ(out.error.rmse, ref.error.rmse);
        EXPECT_EQ(out.error.maxError, ref.error.maxError);
        EXPECT_EQ(out.error.minValue, ref.error.minValue);
      }
    }
  }
  // Bounds 1% away from the RMSE are decided by the residual alone (all but the 1000-offset block,
  // where the sums cancel more), the bound at the RMSE itself never is.
  std::printf("decided without measuring: %d of %d\n", decided, calls);
  EXPECT_GE(decided, calls * 3 / 5);
}

TEST(FitWithin, RangeBracketsTheResidual) {
  // |d|^2 = 100 on 100 samples, c^T A^T A c = 99: residual 1, RMSE 0.1.
  const RmseRange r = rmseRange(100.0, 99.0, 1.0, 100);
  EXPECT_LT(r.lo, 0.1);
  EXPECT_GT(r.lo, 0.1 - 1e-6);
  EXPECT_GT(r.hi, 0.1 + 5.9e-8);  // half an ulp of a float32 control point of 1
  EXPECT_LT(r.hi, 0.1 + 1e-6);
  // A residual below the rounding slack: the lower end is 0, never negative or NaN.
  EXPECT_EQ(rmseRange(1.0, 1.0, 1.0, 8).lo, 0.0);
}

TEST(FitWithin, ChangedControlPointsAgreeWithTheMeasuredError) {
  BlockFitter fitter;
  int decided = 0, calls = 0;
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    const FitResult fr = fitter.fit(c.samples.data(), c.n, clampNcp(9, c.n, {2, 2, 2}), 2);
    for (double step : {1e-6, 1e-5, 1e-4, 1e-3, 1e-2}) {
      FitResult q = fr;
      for (float& v : q.control) v = float(std::round(double(v) / step) * step);
      const double rmse = fitter.error(c.samples.data(), c.n, q).rmse;
      for (double factor : {0.5, 0.99, 1.0, 1.01, 2.0}) {
        const double bound = factor == 1.0 ? rmse : rmse * factor;
        FitResult changed = q;
        const bool ok = fitter.changeWithin(c.samples.data(), c.n, fr, changed, bound);
        ++calls;
        EXPECT_EQ(ok, rmse <= bound) << "step " << step << " factor " << factor;
        if (!changed.errorMeasured) ++decided;
        fitter.measure(c.samples.data(), c.n, changed);
        EXPECT_EQ(changed.error.rmse, rmse);
      }
    }
  }
  std::printf("decided without measuring: %d of %d\n", decided, calls);
  EXPECT_GE(decided, calls * 3 / 5);
  FitResult other = fitter.fit(cases()[0].samples.data(), {17, 17, 17}, {5, 5, 5}, 2);
  const FitResult fr = fitter.fit(cases()[0].samples.data(), {17, 17, 17}, {6, 6, 6}, 2);
  EXPECT_THROW(fitter.changeWithin(cases()[0].samples.data(), {17, 17, 17}, fr, other, 1.0),
               InvalidArgument);
}

TEST(FitWithin, NonFiniteSamplesAreRefusedLikeFitInto) {
  std::vector<float> v = cases()[0].samples;
  v[100] = std::nanf("");
  BlockFitter fitter;
  FitResult out;
  const double squares = sumOfSquares(v.data(), {17, 17, 17});
  EXPECT_FALSE(std::isfinite(squares));
  EXPECT_THROW(fitter.fitWithin(v.data(), {17, 17, 17}, {9, 9, 9}, 2, 1e-3, squares, out),
               NumericError);
}
