// SPDX-License-Identifier: BSD-3-Clause
// Knots, span search, basis functions and their derivatives, and evaluateModel.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "afam/spline/basis.hpp"
#include "afam/spline/evaluate.hpp"
#include "small_model.hpp"

namespace {

using afam::kMaxOrder;
using afam::Knots;

TEST(Knots, ClampedDeBoorAveragedInteriorKnots) {
  for (int p = 1; p <= 5; ++p)
    for (int ncp = p + 1; ncp <= 40; ++ncp) {
      const Knots k = Knots::make(ncp, p);
      for (int i = 0; i <= p; ++i) EXPECT_EQ(k.knot<double>(i), 0.0);
      for (int i = ncp; i <= ncp + p; ++i) EXPECT_EQ(k.knot<double>(i), 1.0);
      for (int j = 1; j <= ncp - p - 1; ++j) {
        // de Boor average of p consecutive virtual uniform parameters v_k = k / (ncp - 1).
        double avg = 0;
        for (int l = j; l < j + p; ++l) avg += double(l) / double(ncp - 1);
        avg /= p;
        EXPECT_NEAR(k.knot<double>(p + j), avg, 1e-15) << "p=" << p << " ncp=" << ncp;
        EXPECT_GT(k.knot<double>(p + j), k.knot<double>(p + j - 1));
        EXPECT_NEAR(k.knot<float>(p + j), avg, 1e-6);
      }
    }
}

TEST(Knots, SpanAtEndsKnotsAndMidpoints) {
  for (int p = 1; p <= 5; ++p)
    for (int ncp = p + 1; ncp <= 30; ++ncp) {
      const Knots k = Knots::make(ncp, p);
      EXPECT_EQ(k.span(0.0f), p);
      EXPECT_EQ(k.span(0.0), p);
      EXPECT_EQ(k.span(1.0f), ncp - 1);
      EXPECT_EQ(k.span(1.0), ncp - 1);
      EXPECT_EQ(k.span(-0.3f), p);
      EXPECT_EQ(k.span(1.7f), ncp - 1);
      for (int s = p; s < ncp; ++s) {
        const double a = k.knot<double>(s), b = k.knot<double>(s + 1);
        EXPECT_EQ(k.span(0.5 * (a + b)), s);
        EXPECT_EQ(k.span(float(0.5 * (a + b))), s);
        // Exactly at an interior knot either neighbouring span is correct (C^{p-1} continuity).
        if (s > p) {
          const int at = k.span(float(a));
          EXPECT_TRUE(at == s || at == s - 1) << "knot " << s << " span " << at;
        }
      }
    }
}

TEST(Basis, PartitionOfUnityAndNonNegativity) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (int p = 0; p <= 5; ++p)
    for (int ncp = p + 1; ncp <= (p == 0 ? 1 : 25); ++ncp) {
      const Knots k = Knots::make(ncp, p);
      std::vector<double> us = {0.0, 1.0};
      for (int i = 0; i <= ncp + p; ++i) us.push_back(k.knot<double>(i));
      for (int i = 0; i < 50; ++i) us.push_back(uni(rng));
      for (double u : us) {
        double N[kMaxOrder], dN[kMaxOrder];
        const int s = k.span(u);
        afam::basisFunctionsAndDerivatives(k, s, u, N, dN);
        double sum = 0, dsum = 0;
        for (int r = 0; r <= p; ++r) {
          EXPECT_GE(N[r], -1e-15) << "p=" << p << " ncp=" << ncp << " u=" << u << " r=" << r;
          sum += N[r];
          dsum += dN[r];
        }
        EXPECT_NEAR(sum, 1.0, 1e-14) << "p=" << p << " ncp=" << ncp << " u=" << u;
        EXPECT_NEAR(dsum, 0.0, 1e-11 * ncp) << "p=" << p << " ncp=" << ncp << " u=" << u;
        float Nf[kMaxOrder];
        afam::basisFunctions(k, k.span(float(u)), float(u), Nf);
        float sumf = 0;
        for (int r = 0; r <= p; ++r) sumf += Nf[r];
        EXPECT_NEAR(sumf, 1.0f, 4e-7f);
      }
    }
}

TEST(Basis, ValueOnlyPathEqualsValueOfDerivativePath) {
  for (int p = 1; p <= 5; ++p) {
    const Knots k = Knots::make(17, p);
    for (int i = 0; i <= 100; ++i) {
      const double u = i / 100.0;
      double N[kMaxOrder], M[kMaxOrder], dN[kMaxOrder];
      const int s = k.span(u);
      afam::basisFunctions(k, s, u, N);
      afam::basisFunctionsAndDerivatives(k, s, u, M, dN);
      for (int r = 0; r <= p; ++r) EXPECT_DOUBLE_EQ(N[r], M[r]);
    }
  }
}

/// Spline f(u) = sum c_g N_g(u) on one axis, in double.
double spline1d(const Knots& k, const std::vector<double>& c, double u, double* derivative) {
  double N[kMaxOrder], dN[kMaxOrder];
  const int s = k.span(u);
  afam::basisFunctionsAndDerivatives(k, s, u, N, dN);
  double f = 0, df = 0;
  for (int r = 0; r <= k.degree; ++r) {
    f += c[size_t(s - k.degree + r)] * N[r];
    df += c[size_t(s - k.degree + r)] * dN[r];
  }
  if (derivative) *derivative = df;
  return f;
}

TEST(Basis, DerivativeMatchesCentralDifferences) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> uni(0.0, 1.0), coef(-1.0, 1.0);
  for (int p = 1; p <= 5; ++p)
    for (int ncp : {p + 1, p + 2, 9, 32}) {
      const Knots k = Knots::make(ncp, p);
      std::vector<double> c(static_cast<size_t>(ncp));
      for (auto& x : c) x = coef(rng);
      const double h = 1e-6;
      for (int i = 0; i < 200; ++i) {
        const double u = h + (1 - 2 * h) * uni(rng);
        // Degree 1 has kinks at knots: stay away from them.
        if (p == 1) {
          const int s = k.span(u);
          if (u - k.knot<double>(s) < 2 * h || k.knot<double>(s + 1) - u < 2 * h) continue;
        }
        double d;
        spline1d(k, c, u, &d);
        const double fd =
            (spline1d(k, c, u + h, nullptr) - spline1d(k, c, u - h, nullptr)) / (2 * h);
        EXPECT_NEAR(d, fd, 1e-6 * (1 + std::fabs(d)) * ncp)
            << "p=" << p << " ncp=" << ncp << " u=" << u;
      }
    }
}

TEST(Basis, DegreeZeroSingleControlPoint) {
  const Knots k = Knots::make(1, 0);
  for (float u : {0.f, 0.5f, 1.f, -2.f, 3.f}) {
    EXPECT_EQ(k.span(u), 0);
    float N[kMaxOrder], dN[kMaxOrder];
    afam::basisFunctionsAndDerivatives(k, 0, afam::clampParameter(u), N, dN);
    EXPECT_EQ(N[0], 1.f);
    EXPECT_EQ(dN[0], 0.f);
  }
}

/// Reference tensor-product value and gradient in double straight from the definition.
double referenceValue(const SmallModel& m, double u, double v, double w, double* g) {
  const Knots* k = m.view.knots;
  double N[3][kMaxOrder], dN[3][kMaxOrder];
  int s[3];
  const double t[3] = {u, v, w};
  for (int a = 0; a < 3; ++a) {
    s[a] = k[a].span(t[a]);
    afam::basisFunctionsAndDerivatives(k[a], s[a], t[a], N[a], dN[a]);
  }
  double f = 0;
  g[0] = g[1] = g[2] = 0;
  for (int c = 0; c <= k[2].degree; ++c)
    for (int b = 0; b <= k[1].degree; ++b)
      for (int a = 0; a <= k[0].degree; ++a) {
        const int ix = s[0] - k[0].degree + a, iy = s[1] - k[1].degree + b,
                  iz = s[2] - k[2].degree + c;
        const double cp = m.control[(size_t(iz) * k[1].ncp + iy) * k[0].ncp + ix];
        f += cp * N[0][a] * N[1][b] * N[2][c];
        g[0] += cp * dN[0][a] * N[1][b] * N[2][c];
        g[1] += cp * N[0][a] * dN[1][b] * N[2][c];
        g[2] += cp * N[0][a] * N[1][b] * dN[2][c];
      }
  return f;
}

TEST(Evaluate, ValueAndGradientMatchDoubleReference) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> uni(0.f, 1.f);
  for (int p = 1; p <= 3; ++p) {
    SmallModel m(9, 7, 5, p, p, std::min(p, 3), 11u + unsigned(p));
    for (int i = 0; i < 500; ++i) {
      const float u = uni(rng), v = uni(rng), w = uni(rng);
      double gref[3];
      const double ref = referenceValue(m, u, v, w, gref);
      float g[3];
      const float val = afam::evaluateModel<true>(m.view, u, v, w, g);
      const float valOnly = afam::evaluateModel<false>(m.view, u, v, w, nullptr);
      EXPECT_NEAR(val, ref, 2e-6);
      EXPECT_EQ(val, valOnly);
      for (int a = 0; a < 3; ++a) EXPECT_NEAR(g[a], gref[a], 2e-5 * (1 + std::fabs(gref[a])));
    }
  }
}

TEST(Evaluate, ParametersAtZeroOneAndOutsideAreClamped) {
  SmallModel m(6, 5, 4, 2, 2, 2, 5u);
  const float corner000 = afam::evaluateModel<false>(m.view, 0.f, 0.f, 0.f, nullptr);
  const float corner111 = afam::evaluateModel<false>(m.view, 1.f, 1.f, 1.f, nullptr);
  // Clamped knots interpolate the corner control points.
  EXPECT_NEAR(corner000, m.control.front(), 1e-7);
  EXPECT_NEAR(corner111, m.control.back(), 1e-6);
  EXPECT_EQ(afam::evaluateModel<false>(m.view, -0.5f, -1e30f, -0.0f, nullptr), corner000);
  EXPECT_EQ(afam::evaluateModel<false>(m.view, 1.5f, 1e30f, std::numeric_limits<float>::infinity(),
                                       nullptr),
            corner111);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(afam::evaluateModel<false>(m.view, nan, nan, nan, nullptr), corner000);
  float g[3], g0[3];
  EXPECT_EQ(afam::evaluateModel<true>(m.view, 1.25f, 0.5f, -3.f, g),
            afam::evaluateModel<true>(m.view, 1.f, 0.5f, 0.f, g0));
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(g[a], g0[a]);
    EXPECT_TRUE(std::isfinite(g[a]));
  }
}

TEST(Evaluate, GradientMatchesFiniteDifferencesOfValue) {
  SmallModel m(12, 10, 8, 2, 2, 2, 9u);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> uni(0.05, 0.95);
  for (int i = 0; i < 200; ++i) {
    const double u = uni(rng), v = uni(rng), w = uni(rng);
    double g[3], tmp[3];
    referenceValue(m, u, v, w, g);
    const double h = 1e-6;
    const double fd[3] = {
        (referenceValue(m, u + h, v, w, tmp) - referenceValue(m, u - h, v, w, tmp)) / (2 * h),
        (referenceValue(m, u, v + h, w, tmp) - referenceValue(m, u, v - h, w, tmp)) / (2 * h),
        (referenceValue(m, u, v, w + h, tmp) - referenceValue(m, u, v, w - h, tmp)) / (2 * h)};
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(g[a], fd[a], 1e-5 * (1 + std::fabs(g[a])));
  }
}

}  // namespace

namespace {

TEST(Basis, ClosedFormMatchesRecurrence) {
  // p = 1 and p = 2 take closed forms on every span (end spans included), p = 3 on interior
  // spans; compare with the recurrence by evaluating it directly.
  for (int p = 1; p <= 3; ++p)
    for (int ncp : {p + 1, p + 2, 2 * p + 2, 9, 32, 128}) {
      const Knots k = Knots::make(ncp, p);
      for (int i = 0; i <= 400; ++i) {
        const double u = i / 400.0;
        const int s = k.span(u);
        double N[kMaxOrder], dN[kMaxOrder], R[kMaxOrder], lower[kMaxOrder];
        afam::basisFunctionsAndDerivatives(k, s, u, N, dN);
        afam::basisOfDegree(k, s, u, p, R);
        afam::basisOfDegree(k, s, u, p - 1, lower);
        for (int r = 0; r <= p; ++r) {
          EXPECT_NEAR(N[r], R[r], 1e-13) << "p=" << p << " ncp=" << ncp << " u=" << u;
          // Derivative from the degree p-1 functions (The NURBS Book eq. 2.9).
          const int g = s - p + r;
          const double a = r >= 1 ? lower[r - 1] : 0.0, b = r <= p - 1 ? lower[r] : 0.0;
          const double da = k.knot<double>(g + p) - k.knot<double>(g);
          const double db = k.knot<double>(g + p + 1) - k.knot<double>(g + 1);
          const double ref = p * ((da != 0 ? a / da : 0.0) - (db != 0 ? b / db : 0.0));
          EXPECT_NEAR(dN[r], ref, 1e-11 * ncp) << "p=" << p << " ncp=" << ncp << " u=" << u;
        }
        float Nf[kMaxOrder], dNf[kMaxOrder];
        afam::basisFunctionsAndDerivatives(k, k.span(float(u)), float(u), Nf, dNf);
        // float(u) carries a rounding of ~6e-8 that the basis amplifies by up to p / h.
        if (k.span(float(u)) == s) {
          for (int r = 0; r <= p; ++r) EXPECT_NEAR(Nf[r], N[r], 1e-6 + 2e-7 * ncp);
        }
      }
    }
}

}  // namespace
