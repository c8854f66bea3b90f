// SPDX-License-Identifier: BSD-3-Clause
// evaluateModelBatch against the single-point evaluateModel: value and gradient, p = 1..5,
// several NCPs, random points, points exactly on knots, the domain ends and outside them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "afam/spline/evaluate.hpp"
#include "afam/spline/evaluate_batch.hpp"
#include "small_model.hpp"

namespace {

using afam::Knots;

/// Random points, then on each axis every knot (with the other two random), the corners
/// 0 and 1, and parameters outside [0, 1] (clamped by both paths).
std::vector<float> testPoints(const afam::ModelView& m, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uni(0.f, 1.f);
  std::vector<float> uvw;
  for (int i = 0; i < 1001; ++i)
    for (int a = 0; a < 3; ++a) uvw.push_back(uni(rng));
  for (int axis = 0; axis < 3; ++axis) {
    const Knots& k = m.knots[axis];
    for (int i = 0; i <= k.ncp + k.degree; ++i) {
      float x[3] = {uni(rng), uni(rng), uni(rng)};
      x[axis] = k.knot<float>(i);
      uvw.insert(uvw.end(), x, x + 3);
      for (float& c : x) c = k.knot<float>(i);  // a knot on every axis at once
      uvw.insert(uvw.end(), x, x + 3);
    }
  }
  for (float c : {0.f, 1.f})
    for (float d : {0.f, 1.f})
      for (float e : {0.f, 1.f}) uvw.insert(uvw.end(), {c, d, e});
  const float nan = std::numeric_limits<float>::quiet_NaN();
  uvw.insert(uvw.end(), {-0.25f, 1.25f, 0.5f, -0.f, 1e30f, nan, std::nextafter(1.f, 2.f), -1e-30f,
                         std::nextafter(0.f, 1.f)});
  return uvw;
}

void expectClose(float batch, float single, const char* what, size_t i) {
  const double a = batch, b = single;
  EXPECT_LE(std::fabs(a - b), 1e-12 * std::max(std::fabs(a), std::fabs(b)))
      << what << " at point " << i << ": batch " << a << ", single " << b;
}

void expectWidthMatchesSinglePoint(int lanes, const afam::ModelView& m,
                                   const std::vector<float>& uvw) {
  const size_t n = uvw.size() / 3;
  std::vector<float> value(n), gradient(3 * n), valueOnly(n);
  afam::detail::evaluateModelBatchLanes(lanes, m, uvw.data(), n, value.data(), gradient.data());
  afam::detail::evaluateModelBatchLanes(lanes, m, uvw.data(), n, valueOnly.data(), nullptr);
  for (size_t i = 0; i < n; ++i) {
    const float* x = &uvw[3 * i];
    float g[3];
    const float v = afam::evaluateModel<true>(m, x[0], x[1], x[2], g);
    expectClose(value[i], v, "value", i);
    for (int a = 0; a < 3; ++a) expectClose(gradient[3 * i + a], g[a], "gradient", i);
    expectClose(valueOnly[i], afam::evaluateModel<false>(m, x[0], x[1], x[2], nullptr),
                "value only", i);
    ASSERT_FALSE(::testing::Test::HasFailure())
        << "p " << m.knots[0].degree << ", ncp " << m.knots[0].ncp << " x " << m.knots[1].ncp
        << " x " << m.knots[2].ncp;
  }
}

/// Every SIMD width this CPU runs (4, and 8 with AVX2), each against evaluateModel.
void expectBatchMatchesSinglePoint(const afam::ModelView& m, const std::vector<float>& uvw) {
  for (int lanes = 4; lanes <= afam::detail::batchLanes(); lanes *= 2) {
    SCOPED_TRACE(testing::Message() << lanes << " lanes");
    expectWidthMatchesSinglePoint(lanes, m, uvw);
  }
}

TEST(EvaluateBatch, MatchesSinglePointForDegreesOneToFive) {
  for (int p = 1; p <= 5; ++p)
    for (int ncp : {p + 1, p + 2, 2 * p + 3, 9, 32}) {
      const SmallModel m(ncp, ncp, ncp, p, p, p, unsigned(100 * p + ncp));
      expectBatchMatchesSinglePoint(m.view, testPoints(m.view, unsigned(7 * p + ncp)));
    }
}

TEST(EvaluateBatch, MatchesSinglePointOnAnisotropicModels) {
  for (int p = 1; p <= 5; ++p) {
    const SmallModel m(p + 1, 2 * p + 5, 17, p, p, p, unsigned(p));
    expectBatchMatchesSinglePoint(m.view, testPoints(m.view, unsigned(p + 50)));
    const SmallModel t(33, p + 2, p + 1, p, p, p, unsigned(p + 9));
    expectBatchMatchesSinglePoint(t.view, testPoints(t.view, unsigned(p + 60)));
  }
  // Mixed degrees take the per-point path.
  const SmallModel mixed(8, 9, 10, 2, 3, 2, 3u);
  expectBatchMatchesSinglePoint(mixed.view, testPoints(mixed.view, 4u));
}

TEST(EvaluateBatch, AnyCountIncludingPartialBlocks) {
  const SmallModel m(12, 12, 12, 2, 2, 2, 5u);
  const std::vector<float> all = testPoints(m.view, 6u);
  for (size_t n : {size_t(0), size_t(1), size_t(3), size_t(4), size_t(63), size_t(64), size_t(65),
                   size_t(130)}) {
    std::vector<float> uvw(all.begin(), all.begin() + std::ptrdiff_t(3 * n));
    expectBatchMatchesSinglePoint(m.view, uvw);
  }
}

}  // namespace
