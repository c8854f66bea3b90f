// SPDX-License-Identifier: BSD-3-Clause
// The interpolant's decoding one line at a time (interpolation_passes.hpp, what the GPU decoder
// runs) against BlockFitter's fit at NCP = n (what the CPU decoder runs): the same control points
// bit for bit, at every degree, on axes of one to a hundred samples, on smooth, noisy and extreme
// samples; and roundedPoint against roundPoints.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "afam/format/rounded_points.hpp"
#include "afam/spline/fit.hpp"
#include "afam/spline/interpolation_passes.hpp"

using namespace afam;

namespace {

/// The control points of the interpolant through `samples` (n per axis, x fastest) by the passes,
/// as a decoder of degree `degree` fits them (fit.hpp's effective degree per axis).
std::vector<float> interpolateByLines(const std::vector<float>& samples, Int3 n, int degree) {
  InterpolationAxis axis[3];
  InterpolationAxisView view[3];
  for (int a = 0; a < 3; ++a) {
    axis[a] = interpolationAxis(n[a], effectiveDegree(degree, n[a]));
    view[a] = axis[a].view();
  }
  const size_t count = samples.size();
  std::vector<double> a(count), b(count);
  for (int p = 0; p < kInterpolationPasses; ++p) {
    const auto pass = InterpolationPass(p);
    for (int64_t line = 0; line < interpolationLines(pass, n); ++line)
      interpolationPassLine(pass, view, n, line, samples.data(), a.data(), b.data());
  }
  std::vector<float> out(count);
  for (size_t i = 0; i < count; ++i) out[i] = float(a[i]);
  return out;
}

size_t differingBits(const std::vector<float>& x, const std::vector<float>& y) {
  size_t d = 0;
  for (size_t i = 0; i < x.size(); ++i) d += std::memcmp(&x[i], &y[i], sizeof(float)) != 0;
  return d;
}

std::vector<float> randomSamples(Int3 n, std::mt19937& rng, double scale, bool smooth) {
  std::normal_distribution<double> noise(0.0, 1.0);
  const size_t count = size_t(n[0]) * size_t(n[1]) * size_t(n[2]);
  std::vector<float> s(count);
  size_t i = 0;
  for (int z = 0; z < n[2]; ++z)
    for (int y = 0; y < n[1]; ++y)
      for (int x = 0; x < n[0]; ++x, ++i)
        s[i] = float(scale *
                     (smooth ? std::sin(0.2 * x + 0.1 * y) * std::cos(0.15 * z) + 0.01 * noise(rng)
                             : noise(rng)));
  return s;
}

}  // namespace

TEST(InterpolationPasses, EqualTheFittersInterpolantBitForBit) {
  std::mt19937 rng(11);
  BlockFitter fitter;
  FitResult fit;
  const Int3 shapes[] = {{54, 66, 56}, {1, 7, 9}, {2, 2, 2}, {3, 1, 5}, {100, 4, 3}, {17, 33, 9}};
  size_t compared = 0, differing = 0;
  for (const Int3 n : shapes)
    for (int degree = 1; degree <= 3; ++degree)
      for (const double scale : {1.0, 255.0, 1e30, 1e-30})
        for (const bool smooth : {true, false}) {
          const std::vector<float> s = randomSamples(n, rng, scale, smooth);
          fitter.fitInto(s.data(), n, n, degree, false, fit);
          const std::vector<float> lines = interpolateByLines(s, n, degree);
          ASSERT_EQ(lines.size(), fit.control.size());
          const size_t d = differingBits(lines, fit.control);
          differing += d;
          compared += lines.size();
          EXPECT_EQ(d, 0u) << n[0] << "x" << n[1] << "x" << n[2] << " degree " << degree
                           << " scale " << scale;
        }
  std::printf("[interpolation-passes] %zu control points compared, %zu differ\n", compared,
              differing);
  EXPECT_GT(compared, 1000000u);
}

TEST(InterpolationPasses, AxisTablesAreRefusedWhereNoInterpolationExists) {
  EXPECT_THROW(interpolationAxis(0, 0), InvalidArgument);
  EXPECT_THROW(interpolationAxis(3, 3), InvalidArgument);  // degree 3 needs 4 samples
  EXPECT_THROW(interpolationAxis(9, -1), InvalidArgument);
  const InterpolationAxis a = interpolationAxis(9, 2);
  EXPECT_EQ(a.rowFirst.size(), 9u);
  EXPECT_EQ(a.invDiag.size(), 9u);
}

TEST(InterpolationPasses, RoundedPointEqualsRoundPoints) {
  std::mt19937 rng(3);
  std::normal_distribution<double> value(0.0, 100.0);
  const double q = 0.0625 / 3;  // a step whose inverse is not exact
  std::vector<float> points(10000);
  for (float& p : points) p = float(value(rng));
  points[0] = float(q * 2.5);  // ties
  points[1] = float(-q * 3.5);
  points[2] = std::numeric_limits<float>::max();
  std::vector<float> rounded = points;
  std::vector<int64_t> codes(points.size());
  const bool all = roundPoints(rounded.data(), rounded.size(), q, codes.data());
  bool each = true;
  size_t differ = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    float v;
    double k;
    each &= roundedPoint(points[i], q, 1.0 / q, &v, &k);
    differ += std::memcmp(&v, &rounded[i], sizeof v) != 0 || int64_t(k) != codes[i];
  }
  EXPECT_EQ(differ, 0u);
  EXPECT_EQ(each, all);
  float v;
  double k;
  EXPECT_FALSE(roundedPoint(std::numeric_limits<float>::quiet_NaN(), q, 1.0 / q, &v, &k));
  EXPECT_FALSE(roundedPoint(std::numeric_limits<float>::infinity(), q, 1.0 / q, &v, &k));
  EXPECT_TRUE(roundedPoint(1.0f, q, 1.0 / q, &v, &k));
  EXPECT_EQ(v, float(k * q));
}
