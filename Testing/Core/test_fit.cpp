// SPDX-License-Identifier: BSD-3-Clause
// Separable least-squares fit: equality with the dense tensor solve, reproduction, error metrics,
// grid evaluation, argument checks, and the Marschner-Lobb reference function.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/spline/evaluate.hpp"
#include "afam/spline/fit.hpp"
#include "afam/volume/marschner_lobb.hpp"

namespace {

using Int3 = std::array<int, 3>;

std::vector<float> sampleBlock(Int3 n, const std::function<double(double, double, double)>& f) {
  std::vector<float> out(static_cast<size_t>(n[0]) * n[1] * n[2]);
  auto param = [](int k, int count) { return count > 1 ? double(k) / (count - 1) : 0.0; };
  for (int z = 0; z < n[2]; ++z)
    for (int y = 0; y < n[1]; ++y)
      for (int x = 0; x < n[0]; ++x)
        out[(size_t(z) * n[1] + y) * n[0] + x] =
            float(f(param(x, n[0]), param(y, n[1]), param(z, n[2])));
  return out;
}

std::vector<float> mlBlock(int n) {
  std::vector<float> b(static_cast<size_t>(n) * n * n);
  afam::marschnerLobbSlab(afam::MarschnerLobb{}, {n, n, n}, 0, n, b.data());
  return b;
}

/// Dense n x ncp collocation matrix of one axis, straight from the basis header.
Eigen::MatrixXd collocation(int n, int ncp, int p) {
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, ncp);
  const afam::Knots k = afam::Knots::make(ncp, p);
  double N[afam::kMaxOrder];
  for (int i = 0; i < n; ++i) {
    const double u = n > 1 ? double(i) / (n - 1) : 0.0;
    const int s = k.span(u);
    afam::basisFunctions(k, s, u, N);
    for (int r = 0; r <= p; ++r) a(i, s - p + r) = N[r];
  }
  return a;
}

void expectSeparableEqualsDense(Int3 n, Int3 ncp, int degree, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uni(-1.f, 1.f);
  std::vector<float> d(static_cast<size_t>(n[0]) * n[1] * n[2]);
  for (auto& x : d) x = uni(rng);
  afam::BlockFitter fitter;
  const afam::FitResult fit = fitter.fit(d.data(), n, ncp, degree);
  // Full tensor system: row (x,y,z) of Az (x) Ay (x) Ax, x fastest.
  const Eigen::MatrixXd ax = collocation(n[0], ncp[0], fit.degree[0]);
  const Eigen::MatrixXd ay = collocation(n[1], ncp[1], fit.degree[1]);
  const Eigen::MatrixXd az = collocation(n[2], ncp[2], fit.degree[2]);
  Eigen::MatrixXd full(int(d.size()), ncp[0] * ncp[1] * ncp[2]);
  for (int z = 0; z < n[2]; ++z)
    for (int y = 0; y < n[1]; ++y)
      for (int x = 0; x < n[0]; ++x)
        for (int k = 0; k < ncp[2]; ++k)
          for (int j = 0; j < ncp[1]; ++j)
            for (int i = 0; i < ncp[0]; ++i)
              full((z * n[1] + y) * n[0] + x, (k * ncp[1] + j) * ncp[0] + i) =
                  az(z, k) * ay(y, j) * ax(x, i);
  Eigen::VectorXd rhs(int(d.size()));
  for (int i = 0; i < rhs.size(); ++i) rhs(i) = d[size_t(i)];
  const Eigen::VectorXd dense = full.colPivHouseholderQr().solve(rhs);
  ASSERT_EQ(fit.control.size(), size_t(dense.size()));
  const double scale = dense.cwiseAbs().maxCoeff();
  for (int i = 0; i < dense.size(); ++i)
    EXPECT_NEAR(fit.control[size_t(i)], dense(i), 2e-7 * scale) << "control " << i;
  // Its error statistics are those of the dense residual, up to the float32 rounding of the
  // control points (which dominates at interpolation, where the residual is ~0).
  const double denseRmse = std::sqrt((full * dense - rhs).squaredNorm() / double(rhs.size()));
  EXPECT_NEAR(fit.error.rmse, denseRmse, 1e-6 * denseRmse + 1e-6 * scale);
}

TEST(Fit, SeparableEqualsDenseTensorLeastSquares) {
  expectSeparableEqualsDense({7, 6, 5}, {4, 4, 3}, 2, 1u);
  expectSeparableEqualsDense({7, 6, 5}, {4, 4, 4}, 3, 2u);
  expectSeparableEqualsDense({7, 6, 5}, {6, 5, 5}, 3, 3u);
  expectSeparableEqualsDense({9, 3, 8}, {5, 2, 7}, 1, 4u);
  expectSeparableEqualsDense({8, 1, 6}, {5, 1, 4}, 2, 5u);  // one-sample-thick slab
  expectSeparableEqualsDense({6, 7, 8}, {6, 7, 8}, 5, 6u);  // interpolation at degree 5
}

/// Separable polynomial of degree q per axis.
double poly(double t, int q, double a) {
  double v = 1.0, tk = 1.0;
  for (int k = 1; k <= q; ++k) {
    tk *= t;
    v += a * (k % 2 ? 1.0 : -0.7) * tk / k;
  }
  return v;
}

TEST(Fit, PolynomialsOfDegreeAtMostPAreReproduced) {
  afam::BlockFitter fitter;
  for (int p = 1; p <= 5; ++p)
    for (int q = 0; q <= p; ++q) {
      const Int3 n{20, 17, 13};
      const auto d = sampleBlock(n, [&](double u, double v, double w) {
        return poly(u, q, 1.3) * poly(v, q, -0.8) + poly(w, q, 2.1);
      });
      const auto [lo, hi] = std::minmax_element(d.begin(), d.end());
      const double range = std::max(1.0, double(*hi - *lo));
      for (Int3 ncp : {Int3{p + 1, p + 1, p + 1}, Int3{9, 7, 6}, Int3{20, 17, 13}}) {
        const afam::FitResult fit = fitter.fit(d.data(), n, ncp, p);
        EXPECT_LE(fit.error.maxError, 4e-7 * std::max(std::fabs(*lo), std::fabs(*hi)) * 4)
            << "p=" << p << " q=" << q << " ncp=" << ncp[0];
        EXPECT_LE(fit.error.rmse, 3e-7 * range) << "p=" << p << " q=" << q;
      }
    }
}

TEST(Fit, ConstantBlocksGiveConstantControlPoints) {
  afam::BlockFitter fitter;
  for (float c : {0.f, 3.25f, -1e-3f, 7e20f})
    for (Int3 n : {Int3{1, 1, 1}, Int3{2, 2, 2}, Int3{16, 16, 16}, Int3{5, 1, 9}, Int3{33, 4, 3}})
      for (int p = 1; p <= 3; ++p) {
        const std::vector<float> d(static_cast<size_t>(n[0]) * n[1] * n[2], c);
        Int3 deg{};
        for (int a = 0; a < 3; ++a) deg[a] = afam::effectiveDegree(p, n[a]);
        for (int ncp : {1, 3, 8, 64}) {
          const afam::FitResult fit = fitter.fit(d.data(), n, afam::clampNcp(ncp, n, deg), p);
          for (float cp : fit.control) EXPECT_NEAR(cp, c, 3e-7 * std::fabs(c));
          EXPECT_LE(fit.error.maxError, 3e-7 * std::fabs(c));
          EXPECT_NEAR(fit.error.minValue, c, 3e-7 * std::fabs(c));
          EXPECT_NEAR(fit.error.maxValue, c, 3e-7 * std::fabs(c));
        }
      }
}

TEST(Fit, ErrorAndGridEvaluationAgreeWithPointEvaluation) {
  const Int3 n{19, 23, 17};
  const auto d = sampleBlock(n, [](double u, double v, double w) {
    return std::sin(7 * u) * std::cos(5 * v) + w * w * w * w;
  });
  afam::BlockFitter fitter;
  for (int p = 1; p <= 4; ++p) {
    const afam::FitResult fit = fitter.fit(d.data(), n, {8, 9, 7}, p);
    std::vector<float> grid;
    fitter.evaluateOnGrid(fit, n, grid);
    std::vector<float> grid2;
    afam::evaluateOnGrid(fit, n, grid2);
    EXPECT_EQ(grid, grid2);
    const afam::ModelView view = fit.view();
    double sum = 0, maxErr = 0, lo = 1e30, hi = -1e30;
    for (int z = 0; z < n[2]; ++z)
      for (int y = 0; y < n[1]; ++y)
        for (int x = 0; x < n[0]; ++x) {
          const size_t i = (size_t(z) * n[1] + y) * n[0] + x;
          const float v = afam::evaluateModel<false>(
              view, float(x) / (n[0] - 1), float(y) / (n[1] - 1), float(z) / (n[2] - 1), nullptr);
          EXPECT_NEAR(grid[i], v, 2e-6);
          const double e = double(grid[i]) - d[i];
          sum += e * e;
          maxErr = std::max(maxErr, std::fabs(e));
          lo = std::min(lo, double(grid[i]));
          hi = std::max(hi, double(grid[i]));
        }
    const afam::ErrorStats s = fitter.error(d.data(), n, fit);
    EXPECT_NEAR(s.rmse, std::sqrt(sum / double(d.size())), 1e-6);
    EXPECT_NEAR(s.maxError, maxErr, 1e-6);
    EXPECT_NEAR(s.minValue, lo, 1e-6);
    EXPECT_NEAR(s.maxValue, hi, 1e-6);
    EXPECT_DOUBLE_EQ(s.rmse, fit.error.rmse);
    EXPECT_DOUBLE_EQ(s.maxError, fit.error.maxError);
  }
}

TEST(Fit, NoErrorPassLeavesErrorZeroAndSameControl) {
  const auto d = mlBlock(24);
  afam::BlockFitter fitter;
  const auto a = fitter.fit(d.data(), {24, 24, 24}, {10, 10, 10}, 2, false);
  const auto b = fitter.fit(d.data(), {24, 24, 24}, {10, 10, 10}, 2, true);
  EXPECT_EQ(a.control, b.control);
  EXPECT_EQ(a.error.rmse, 0.0);
  EXPECT_GT(b.error.rmse, 0.0);
}

TEST(Fit, FitterReuseAcrossShapesMatchesFreshFitter) {
  afam::BlockFitter reused;
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> uni(-1.f, 1.f);
  for (int round = 0; round < 3; ++round)
    for (Int3 n : {Int3{9, 8, 7}, Int3{16, 16, 16}, Int3{4, 12, 2}}) {
      std::vector<float> d(static_cast<size_t>(n[0]) * n[1] * n[2]);
      for (auto& x : d) x = uni(rng);
      const Int3 ncp =
          afam::clampNcp(6, n,
                         {afam::effectiveDegree(2, n[0]), afam::effectiveDegree(2, n[1]),
                          afam::effectiveDegree(2, n[2])});
      afam::BlockFitter fresh;
      const auto a = reused.fit(d.data(), n, ncp, 2);
      const auto b = fresh.fit(d.data(), n, ncp, 2);
      EXPECT_EQ(a.control, b.control);
      EXPECT_EQ(a.error.rmse, b.error.rmse);
      afam::FitResult into;
      reused.fitInto(d.data(), n, ncp, 2, true, into);
      EXPECT_EQ(into.control, a.control);
    }
}

TEST(Fit, HundredsOfShapesKeepEveryFitCorrect) {
  // Regression: the per-axis cache was once cleared between the three look-ups of one fit.
  afam::BlockFitter fitter;
  for (int n = 4; n < 40; ++n)
    for (int ncp = 3; ncp <= std::min(n, 8); ++ncp) {
      const Int3 shape{n, ncp + 1, 3 + n % 5};
      const auto d = sampleBlock(shape, [](double u, double v, double w) { return u + 2 * v - w; });
      const Int3 m = afam::clampNcp(ncp, shape, {2, 2, 2});
      const auto fit = fitter.fit(d.data(), shape, m, 2);
      ASSERT_LT(fit.error.maxError, 1e-5) << n << " " << ncp;
    }
}

TEST(Fit, InvalidArgumentsAreRejectedWithReadableMessages) {
  std::vector<float> d(8 * 8 * 8, 1.f);
  afam::BlockFitter fitter;
  EXPECT_THROW(fitter.fit(d.data(), {8, 8, 8}, {4, 4, 4}, 0), afam::InvalidArgument);
  EXPECT_THROW(fitter.fit(d.data(), {8, 8, 8}, {4, 4, 4}, 6), afam::InvalidArgument);
  EXPECT_THROW(fitter.fit(d.data(), {8, 0, 8}, {4, 4, 4}, 2), afam::InvalidArgument);
  EXPECT_THROW(fitter.fit(d.data(), {8, 8, 8}, {9, 4, 4}, 2), afam::InvalidArgument);
  EXPECT_THROW(fitter.fit(d.data(), {8, 8, 8}, {4, 2, 4}, 2), afam::InvalidArgument);
  EXPECT_THROW(fitter.fit(nullptr, {8, 8, 8}, {4, 4, 4}, 2), afam::InvalidArgument);
  try {
    fitter.fit(d.data(), {8, 8, 8}, {4, 4, 12}, 2);
    FAIL() << "no exception";
  } catch (const afam::Error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("NCP 12"), std::string::npos) << msg;
    EXPECT_NE(msg.find("axis z"), std::string::npos) << msg;
  }
  afam::FitResult bad = fitter.fit(d.data(), {8, 8, 8}, {4, 4, 4}, 2);
  bad.control.pop_back();
  EXPECT_THROW(fitter.error(d.data(), {8, 8, 8}, bad), afam::InvalidArgument);
  EXPECT_THROW(afam::axisConditioning(8, 9, 2), afam::InvalidArgument);
}

TEST(Fit, EffectiveDegreeClampNcpAndPsnr) {
  EXPECT_EQ(afam::effectiveDegree(2, 1), 0);
  EXPECT_EQ(afam::effectiveDegree(2, 2), 1);
  EXPECT_EQ(afam::effectiveDegree(3, 3), 2);
  EXPECT_EQ(afam::effectiveDegree(3, 64), 3);
  EXPECT_EQ(afam::clampNcp(16, {64, 8, 1}, {2, 2, 0}), (Int3{16, 8, 1}));
  EXPECT_EQ(afam::clampNcp(1, {64, 8, 2}, {3, 2, 1}), (Int3{4, 3, 2}));
  EXPECT_DOUBLE_EQ(afam::psnr(0.01, 1.0), 40.0);
  EXPECT_NEAR(afam::psnr(0.5, 2.0), 20 * std::log10(4.0), 1e-12);
  EXPECT_TRUE(std::isinf(afam::psnr(0.0, 1.0)));
}

TEST(MarschnerLobb, KnownValuesAndExactGradient) {
  const afam::MarschnerLobb ml;
  // r = 0, z = 0: (1 + alpha (1 + cos(2 pi fM))) / (2 (1 + alpha)) = (1 + 2 alpha) / (2 + 2 alpha).
  EXPECT_NEAR(ml.valueT<double>(0, 0, 0), 1.5 / 2.5, 1e-12);
  EXPECT_NEAR(ml.valueT<double>(0, 0, 1), 0.5 / 2.5, 1e-12);
  // r = 1: cos(pi/2) = 0, rho = 1.
  EXPECT_NEAR(ml.valueT<double>(1, 0, -1), (2 + 0.5) / 2.5, 1e-12);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> uni(-0.99, 0.99);
  for (const afam::MarschnerLobb m :
       {afam::MarschnerLobb{}, afam::MarschnerLobb{0.05f, 6.f, 0.f, 7.f}}) {
    for (int i = 0; i < 300; ++i) {
      const double s = 0.5 * (m.hi - m.lo);
      const double x = m.lo + s * (1 + uni(rng)), y = m.lo + s * (1 + uni(rng)),
                   z = m.lo + s * (1 + uni(rng));
      double g[3];
      m.gradientT<double>(x, y, z, g);
      const double h = 1e-6 * s;
      const double fd[3] = {
          (m.valueT<double>(x + h, y, z) - m.valueT<double>(x - h, y, z)) / (2 * h),
          (m.valueT<double>(x, y + h, z) - m.valueT<double>(x, y - h, z)) / (2 * h),
          (m.valueT<double>(x, y, z + h) - m.valueT<double>(x, y, z - h)) / (2 * h)};
      for (int a = 0; a < 3; ++a) EXPECT_NEAR(g[a], fd[a], 1e-5 * (1 + std::fabs(g[a])));
      float gf[3];
      m.gradient(float(x), float(y), float(z), gf);
      for (int a = 0; a < 3; ++a) EXPECT_NEAR(gf[a], g[a], 2e-3 * (1 + std::fabs(g[a])));
    }
    // Finite on the axis r = 0.
    double g[3];
    m.gradientT<double>(0.5 * (m.lo + m.hi), 0.5 * (m.lo + m.hi), m.lo, g);
    for (double v : g) EXPECT_TRUE(std::isfinite(v));
  }
}

TEST(MarschnerLobb, SlabsTileTheVolume) {
  const afam::MarschnerLobb ml;
  const std::array<int64_t, 3> dims{13, 11, 9};
  std::vector<float> whole(13 * 11 * 9), parts(13 * 11 * 9);
  afam::marschnerLobbSlab(ml, dims, 0, 9, whole.data());
  afam::marschnerLobbSlab(ml, dims, 0, 4, parts.data());
  afam::marschnerLobbSlab(ml, dims, 4, 5, parts.data() + 13 * 11 * 4);
  EXPECT_EQ(whole, parts);
  EXPECT_NEAR(whole[(size_t(4) * 11 + 5) * 13 + 6], ml.valueT<double>(0, 0, 0), 1e-7);
  EXPECT_NEAR(whole[0], ml.valueT<double>(-1, -1, -1), 1e-7);
  EXPECT_THROW(afam::marschnerLobbSlab(ml, dims, 5, 5, parts.data()), afam::InvalidArgument);
}

/// Relative RMS error of the fitted model's world gradient against ML's exact gradient.
double mlGradientError(int n, int ncp, int p, unsigned seed) {
  const auto d = mlBlock(n);
  const afam::MarschnerLobb ml;
  afam::BlockFitter fitter;
  const afam::FitResult fit = fitter.fit(d.data(), {n, n, n}, {ncp, ncp, ncp}, p, false);
  const afam::ModelView view = fit.view();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uni(0.02f, 0.98f);
  double errSq = 0, refSq = 0;
  for (int i = 0; i < 5000; ++i) {
    const float u = uni(rng), v = uni(rng), w = uni(rng);
    float g[3];
    afam::evaluateModel<true>(view, u, v, w, g);
    double ge[3];
    ml.gradientT<double>(-1 + 2.0 * u, -1 + 2.0 * v, -1 + 2.0 * w, ge);
    for (int a = 0; a < 3; ++a) {
      const double gw = g[a] / 2.0;  // du/dx = 1/2 on [-1, 1]
      errSq += (gw - ge[a]) * (gw - ge[a]);
      refSq += ge[a] * ge[a];
    }
  }
  const double rel = std::sqrt(errSq / refSq);
  std::printf("[ measured ] ML gradient relative RMS error, n %d ncp %d p %d: %.4g\n", n, ncp, p,
              rel);
  return rel;
}

TEST(Fit, GradientOfFittedMarschnerLobbMatchesExactGradient) {
  // ML with fM = 6 has ~6 radial periods across [-1, 1]: 64 samples resolve it coarsely, so the
  // gradient error is set by the sampling; it must shrink at the spline's order as n grows.
  EXPECT_LT(mlGradientError(64, 64, 2, 10u), 0.15);  // measured 0.115
  EXPECT_LT(mlGradientError(64, 64, 3, 10u), 0.07);  // measured 0.047
  EXPECT_LT(mlGradientError(64, 48, 3, 10u), 0.25);  // measured 0.183
  const double fine = mlGradientError(128, 128, 3, 10u);
  EXPECT_LT(fine, 0.01);  // ~h^3: 8x smaller at twice the samples
}

}  // namespace
