// SPDX-License-Identifier: BSD-3-Clause
// Stiff and extreme cases of the spline fit. Each asserts a number that could fail; the measured
// values are printed as "[ measured ]" lines and the bounds carry a margin over them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/spline/fit.hpp"
#include "afam/volume/marschner_lobb.hpp"

namespace {

using Int3 = std::array<int, 3>;

std::vector<float> mlBlock(Int3 n, float alpha = 0.25f) {
  std::vector<float> b(static_cast<size_t>(n[0]) * n[1] * n[2]);
  afam::MarschnerLobb ml;
  ml.alpha = alpha;
  afam::marschnerLobbSlab(ml, {n[0], n[1], n[2]}, 0, n[2], b.data());
  return b;
}

double rangeOf(const std::vector<float>& d) {
  const auto [lo, hi] = std::minmax_element(d.begin(), d.end());
  return double(*hi) - double(*lo);
}

// ---- NCP = n: interpolation must reproduce the samples to float precision ----

class Interpolation : public ::testing::TestWithParam<std::tuple<int, int>> {};

TEST_P(Interpolation, NcpEqualsNReproducesSamples) {
  const int n = std::get<0>(GetParam()), p = std::get<1>(GetParam());
  // ML plus white noise: interpolation has to follow every sample, not just a smooth field.
  auto d = mlBlock({n, n, n});
  std::mt19937 rng(unsigned(n * 10 + p));
  std::uniform_real_distribution<float> noise(-0.05f, 0.05f);
  for (auto& x : d) x += noise(rng);
  afam::BlockFitter fitter;
  const afam::FitResult fit = fitter.fit(d.data(), {n, n, n}, {n, n, n}, p);
  const double range = rangeOf(d);
  std::printf("[ measured ] NCP = n = %d, p = %d: RMSE/range %.3g, max/range %.3g\n", n, p,
              fit.error.rmse / range, fit.error.maxError / range);
  RecordProperty("rmse_over_range", std::to_string(fit.error.rmse / range));
  EXPECT_LE(fit.error.rmse, 1e-6 * range);  // the bar (at n = 128 in particular)
  EXPECT_LE(fit.error.maxError, 1e-5 * range);
  for (float c : fit.control) ASSERT_TRUE(std::isfinite(c));
}

INSTANTIATE_TEST_SUITE_P(Stability, Interpolation,
                         ::testing::Combine(::testing::Values(32, 64, 128),
                                            ::testing::Values(1, 2, 3)));

// ---- Conditioning of every axis system ----

TEST(Stability, AxisConditionNumbersAreBoundedAtEveryNcp) {
  for (int n : {8, 33, 64, 128})
    for (int p = 1; p <= 3; ++p) {
      double worst = 0;
      int worstNcp = 0;
      for (int ncp = p + 1; ncp <= n; ++ncp) {
        const afam::AxisConditioning c = afam::axisConditioning(n, ncp, p);
        ASSERT_TRUE(std::isfinite(c.collocation)) << "n=" << n << " ncp=" << ncp << " p=" << p;
        EXPECT_NEAR(c.normal, c.collocation * c.collocation, 1e-9 * c.normal);
        if (c.collocation > worst) {
          worst = c.collocation;
          worstNcp = ncp;
        }
        EXPECT_LT(c.collocation, 30.0) << "n=" << n << " ncp=" << ncp << " p=" << p;
      }
      std::printf("[ measured ] n = %d, p = %d: worst collocation cond %.3g at NCP %d\n", n, p,
                  worst, worstNcp);
    }
  // Interpolation at NCP = n is the best-conditioned square system (de Boor-averaged knots).
  EXPECT_LT(afam::axisConditioning(128, 128, 3).collocation, 6.0);
}

// ---- Stiff data: steps and single-voxel spikes ----

TEST(Stability, StepOvershootIsBounded) {
  const int n = 32;
  std::vector<float> d(static_cast<size_t>(n) * n * n);
  for (size_t i = 0; i < d.size(); ++i) d[i] = (i % n) < size_t(n / 2) ? 0.f : 1.f;
  afam::BlockFitter fitter;
  for (int p = 1; p <= 3; ++p)
    for (int ncp : {p + 1, 8, 16, 31, 32}) {
      const afam::FitResult fit = fitter.fit(d.data(), {n, n, n}, {ncp, ncp, ncp}, p);
      ASSERT_TRUE(std::isfinite(fit.error.rmse));
      const double over = std::max(fit.error.maxValue - 1.0, 0.0 - fit.error.minValue);
      std::printf("[ measured ] step, p = %d, NCP = %d: overshoot %.4f, RMSE %.4f\n", p, ncp, over,
                  fit.error.rmse);
      EXPECT_LT(over, 0.25) << "p=" << p << " ncp=" << ncp;
      if (ncp == n) {
        EXPECT_LT(fit.error.maxError, 1e-5);
      }
      for (float c : fit.control) ASSERT_TRUE(std::isfinite(c));
    }
}

TEST(Stability, SingleVoxelSpikeStaysBounded) {
  const int n = 17;
  afam::BlockFitter fitter;
  for (int p = 1; p <= 3; ++p)
    for (int ncp : {p + 1, 6, 9, 16, 17}) {
      std::vector<float> d(static_cast<size_t>(n) * n * n, 0.f);
      d[(size_t(8) * n + 8) * n + 8] = 1.f;  // centre
      d[0] = -1.f;                           // corner, opposite sign
      const afam::FitResult fit = fitter.fit(d.data(), {n, n, n}, {ncp, ncp, ncp}, p);
      std::printf("[ measured ] spike, p = %d, NCP = %d: model in [%.4f, %.4f], max error %.4f\n",
                  p, ncp, fit.error.minValue, fit.error.maxValue, fit.error.maxError);
      EXPECT_GT(fit.error.minValue, -1.0 - 0.25);
      EXPECT_LT(fit.error.maxValue, 1.0 + 0.25);
      EXPECT_LE(fit.error.maxError, 1.0 + 1e-6);
      if (ncp == n) {
        EXPECT_LT(fit.error.maxError, 1e-5);
      }
    }
}

// ---- Magnitudes ----

TEST(Stability, ResultsScaleWithTheDataFrom1e30To1eMinus30AndDenormals) {
  const Int3 n{24, 24, 24};
  const auto base = mlBlock(n);
  afam::BlockFitter fitter;
  const afam::FitResult ref = fitter.fit(base.data(), n, {12, 12, 12}, 2);
  const double refRel = ref.error.rmse / rangeOf(base);
  // 1e-40 is a float denormal (below FLT_MIN = 1.2e-38): its samples carry ~5 significant digits.
  for (double scale : {1e30, 1e20, 1e-30, -1e30, 1e-40}) {
    std::vector<float> d(base.size());
    for (size_t i = 0; i < d.size(); ++i) d[i] = float(double(base[i]) * scale);
    const afam::FitResult fit = fitter.fit(d.data(), n, {12, 12, 12}, 2);
    const double rel = fit.error.rmse / rangeOf(d);
    std::printf("[ measured ] scale %.0e: RMSE/range %.6g (unscaled %.6g)\n", scale, rel, refRel);
    for (float c : fit.control) ASSERT_TRUE(std::isfinite(c));
    EXPECT_NEAR(rel, refRel, (std::fabs(scale) < 1e-37 ? 1e-3 : 1e-6) * refRel) << scale;
    // Control points are the unscaled ones times the scale.
    for (size_t i = 0; i < fit.control.size(); i += 97)
      EXPECT_NEAR(double(fit.control[i]) / scale, ref.control[i],
                  (std::fabs(scale) < 1e-37 ? 1e-4 : 1e-6) * (1 + std::fabs(ref.control[i])));
  }
}

TEST(Stability, MixedSignsAndHugeDynamicRange) {
  // Checkerboard of +-1e30 regions and 1e-30 values: dynamic range 1e60, all signs.
  const int n = 20;
  std::vector<float> d(static_cast<size_t>(n) * n * n);
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const bool big = ((x / 5 + y / 5 + z / 5) % 2) == 0;
        const float sign = ((x + y + z) % 3) == 0 ? -1.f : 1.f;
        d[(size_t(z) * n + y) * n + x] = sign * (big ? 1e30f : 1e-30f);
      }
  afam::BlockFitter fitter;
  for (int ncp : {4, 10, 20}) {
    const afam::FitResult fit = fitter.fit(d.data(), {n, n, n}, {ncp, ncp, ncp}, 3);
    for (float c : fit.control) ASSERT_TRUE(std::isfinite(c));
    std::printf("[ measured ] mixed signs 1e30/1e-30, NCP %d: RMSE/range %.4g\n", ncp,
                fit.error.rmse / 2e30);
    EXPECT_LT(fit.error.rmse, 1e30);
    if (ncp == n) {
      EXPECT_LT(fit.error.maxError, 2e30 * 1e-6);
    }
  }
}

TEST(Stability, NearFloatMaxEitherFitsFiniteOrThrowsNumericError) {
  const int n = 12;
  std::vector<float> d(static_cast<size_t>(n) * n * n);
  for (size_t i = 0; i < d.size(); ++i) d[i] = (i % n) < size_t(n / 2) ? -FLT_MAX : FLT_MAX;
  afam::BlockFitter fitter;
  int fitted = 0, refused = 0;
  for (int ncp : {4, 6, 12}) {
    try {
      const afam::FitResult fit = fitter.fit(d.data(), {n, n, n}, {ncp, ncp, ncp}, 3);
      for (float c : fit.control) ASSERT_TRUE(std::isfinite(c));
      EXPECT_TRUE(std::isfinite(fit.error.rmse));
      ++fitted;
    } catch (const afam::NumericError& e) {
      EXPECT_NE(std::string(e.what()).find("overflows float32"), std::string::npos);
      ++refused;
    }
  }
  EXPECT_EQ(fitted + refused, 3);
  // A constant FLT_MAX block is representable exactly.
  std::vector<float> c(static_cast<size_t>(n) * n * n, FLT_MAX);
  const afam::FitResult fit = fitter.fit(c.data(), {n, n, n}, {5, 5, 5}, 2);
  for (float v : fit.control) EXPECT_EQ(v, FLT_MAX);
}

TEST(Stability, ChiFieldWithDynamicRange1e8) {
  const std::string path =
      std::string(AFAM_TEST_DATA_DIR) + "/volumes/chi_field_50x50x50_float32.raw";
  std::ifstream in(path, std::ios::binary);
  ASSERT_TRUE(in) << "cannot open " << path;
  const int n = 50;
  std::vector<float> d(static_cast<size_t>(n) * n * n);
  in.read(reinterpret_cast<char*>(d.data()), std::streamsize(d.size() * sizeof(float)));
  ASSERT_EQ(in.gcount(), std::streamsize(d.size() * sizeof(float)));
  double minAbs = 1e300, maxAbs = 0;
  for (float v : d) {
    ASSERT_TRUE(std::isfinite(v));
    if (v != 0) minAbs = std::min(minAbs, double(std::fabs(v)));
    maxAbs = std::max(maxAbs, double(std::fabs(v)));
  }
  const double range = rangeOf(d);
  std::printf("[ measured ] chi field: |v| in [%.3g, %.3g], range %.3g\n", minAbs, maxAbs, range);
  afam::BlockFitter fitter;
  for (int p = 1; p <= 3; ++p) {
    const afam::FitResult interp = fitter.fit(d.data(), {n, n, n}, {n, n, n}, p);
    std::printf("[ measured ] chi field NCP = 50, p = %d: RMSE/range %.3g, max/range %.3g\n", p,
                interp.error.rmse / range, interp.error.maxError / range);
    EXPECT_LE(interp.error.rmse, 1e-6 * range);
    EXPECT_LE(interp.error.maxError, 1e-5 * range);
    for (int ncp : {8, 25}) {
      const afam::FitResult fit = fitter.fit(d.data(), {n, n, n}, {ncp, ncp, ncp}, p);
      for (float c : fit.control) ASSERT_TRUE(std::isfinite(c));
      EXPECT_TRUE(std::isfinite(fit.error.rmse));
      EXPECT_LT(fit.error.rmse, range);
    }
  }
}

// ---- Non-finite samples ----

TEST(Stability, NonFiniteSampleThrowsNumericErrorNamingTheSample) {
  const int n = 8;
  afam::BlockFitter fitter;
  for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                    -std::numeric_limits<float>::infinity()}) {
    std::vector<float> d(static_cast<size_t>(n) * n * n, 1.f);
    d[(size_t(5) * n + 4) * n + 3] = bad;  // (3, 4, 5), flat index 3 + 4*8 + 5*64 = 355
    try {
      fitter.fit(d.data(), {n, n, n}, {4, 4, 4}, 2);
      FAIL() << "no exception for " << bad;
    } catch (const afam::NumericError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("(3, 4, 5)"), std::string::npos) << msg;
      EXPECT_NE(msg.find("355"), std::string::npos) << msg;
      EXPECT_NE(msg.find(std::isnan(bad) ? "NaN" : "infinite"), std::string::npos) << msg;
    }
  }
  // Last sample too (the scan covers the whole block).
  std::vector<float> d(static_cast<size_t>(n) * n * n, 1.f);
  d.back() = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(fitter.fit(d.data(), {n, n, n}, {4, 4, 4}, 2), afam::NumericError);
}

// ---- Degenerate shapes ----

TEST(Stability, DegenerateShapesTinyAxesSlabsAndNonCubic) {
  afam::BlockFitter fitter;
  struct Case {
    Int3 n;
    int ncp, p;
  };
  for (const Case c :
       {Case{{1, 1, 1}, 1, 2}, Case{{2, 2, 2}, 2, 2}, Case{{3, 3, 3}, 3, 2}, Case{{3, 3, 3}, 3, 3},
        Case{{2, 3, 1}, 3, 3}, Case{{1, 16, 16}, 16, 2}, Case{{16, 1, 16}, 16, 2},
        Case{{16, 16, 1}, 16, 3}, Case{{1, 1, 40}, 40, 3}}) {
    std::mt19937 rng(unsigned(c.n[0] * 100 + c.n[1] * 10 + c.n[2]));
    std::uniform_real_distribution<float> uni(-1.f, 1.f);
    std::vector<float> d(static_cast<size_t>(c.n[0]) * c.n[1] * c.n[2]);
    for (auto& x : d) x = uni(rng);
    Int3 deg{};
    for (int a = 0; a < 3; ++a) deg[a] = afam::effectiveDegree(c.p, c.n[a]);
    const Int3 ncp = afam::clampNcp(c.ncp, c.n, deg);
    EXPECT_EQ(ncp, c.n);  // these requests are all interpolations
    const afam::FitResult fit = fitter.fit(d.data(), c.n, ncp, c.p);
    EXPECT_EQ(fit.degree, deg);
    EXPECT_LT(fit.error.maxError, 3e-6) << c.n[0] << "x" << c.n[1] << "x" << c.n[2];
    // And a least-squares fit with fewer control points where the axis allows it.
    const Int3 fewer = afam::clampNcp(std::max(1, c.ncp / 2), c.n, deg);
    const afam::FitResult ls = fitter.fit(d.data(), c.n, fewer, c.p);
    EXPECT_TRUE(std::isfinite(ls.error.rmse));
    EXPECT_LE(ls.error.rmse, 1.0);
  }
  // 64 x 64 x 68 Marschner-Lobb, non-cubic NCP.
  const Int3 n{64, 64, 68};
  const auto d = mlBlock(n);
  const afam::FitResult fit = fitter.fit(d.data(), n, {32, 40, 34}, 2);
  std::printf("[ measured ] ML 64x64x68, NCP 32x40x34, p 2: RMSE %.4g\n", fit.error.rmse);
  EXPECT_LT(fit.error.rmse, 0.06);
  const afam::FitResult full = fitter.fit(d.data(), n, n, 2);
  EXPECT_LT(full.error.rmse, 1e-6 * rangeOf(d));
}

TEST(Stability, SlabFitEqualsTwoDimensionalFit) {
  // A one-sample-thick slab is a 2D fit: the same whatever axis is thin.
  const int m = 20;
  std::vector<float> d(static_cast<size_t>(m) * m);
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < m; ++i)
      d[size_t(j) * m + i] = std::sin(0.4f * float(i)) * std::cos(0.3f * float(j));
  afam::BlockFitter fitter;
  const auto xy = fitter.fit(d.data(), {m, m, 1}, {9, 7, 1}, 2);
  const auto xz = fitter.fit(d.data(), {m, 1, m}, {9, 1, 7}, 2);
  const auto yz = fitter.fit(d.data(), {1, m, m}, {1, 9, 7}, 2);
  EXPECT_EQ(xy.control, xz.control);
  EXPECT_EQ(xy.control, yz.control);
  EXPECT_DOUBLE_EQ(xy.error.rmse, yz.error.rmse);
}

}  // namespace
