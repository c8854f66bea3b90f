// SPDX-License-Identifier: BSD-3-Clause
// ImageMetrics against values derived by hand: SSIM is a pass bar for image tests, so its window
// (11 x 11 Gaussian, sigma 1.5), its constants (K1 = 0.01, K2 = 0.03 of the peak) and its formula
// are checked on images whose local statistics have a closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "afam/eval/image_metrics.hpp"

using namespace afam;

namespace {

MetricImage imageOf(int w, int h, const std::function<double(int, int)>& value) {
  MetricImage m;
  m.width = w;
  m.height = h;
  m.peak = 255.0;
  m.rgb.resize(size_t(3) * size_t(w) * size_t(h));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c)
        m.rgb[3 * (size_t(y) * size_t(w) + size_t(x)) + size_t(c)] = value(x, y);
  return m;
}

/// Wang et al.'s index of one window from its moments, peak 255.
double ssimOf(double ma, double mb, double va, double vb, double cab) {
  const double c1 = (0.01 * 255) * (0.01 * 255), c2 = (0.03 * 255) * (0.03 * 255);
  return ((2 * ma * mb + c1) * (2 * cab + c2)) / ((ma * ma + mb * mb + c1) * (va + vb + c2));
}

}  // namespace

TEST(ImageMetrics, ConstantImagesGiveTheLuminanceTerm) {
  // No variance anywhere: SSIM = (2 ma mb + C1) / (ma^2 + mb^2 + C1), the same for the windowed
  // index (32 x 32) and the one global window of an image smaller than the window (8 x 8).
  for (const int size : {32, 8}) {
    const MetricImage a = imageOf(size, size, [](int, int) { return 100.0; });
    const MetricImage b = imageOf(size, size, [](int, int) { return 110.0; });
    EXPECT_NEAR(ssim(a, b), 22006.5025 / 22106.5025, 1e-12) << size;
    EXPECT_NEAR(psnr(a, b), 10 * std::log10(255.0 * 255.0 / 100.0), 1e-12) << size;
  }
}

TEST(ImageMetrics, StripesOfScaledContrastMatchTheClosedForm) {
  // a = m + A (-1)^x, b = m + k A (-1)^x. Under the normalised Gaussian weights w_j (j = -5..5) a
  // window centred on column x sees mean m + A s (-1)^x with s = sum_j w_j (-1)^j, variance
  // A^2 (1 - s^2); b the same with kA, and covariance k A^2 (1 - s^2). Half the 22 valid columns
  // have each sign.
  double w[11], total = 0, s = 0;
  for (int j = -5; j <= 5; ++j) total += (w[j + 5] = std::exp(-double(j * j) / (2 * 1.5 * 1.5)));
  for (int j = -5; j <= 5; ++j) s += (j % 2 == 0 ? 1 : -1) * w[j + 5] / total;
  const double m = 120, A = 40, k = 0.5;
  const MetricImage a = imageOf(32, 32, [&](int x, int) { return m + A * (x % 2 ? -1 : 1); });
  const MetricImage b = imageOf(32, 32, [&](int x, int) { return m + k * A * (x % 2 ? -1 : 1); });
  double expected = 0;
  for (const double sign : {1.0, -1.0}) {
    const double va = A * A * (1 - s * s);
    expected += 0.5 * ssimOf(m + A * s * sign, m + k * A * s * sign, va, k * k * va, k * va);
  }
  EXPECT_NEAR(ssim(a, b), expected, 1e-9);
  EXPECT_LT(expected, 0.9) << "halving the contrast must cost SSIM (the check has teeth)";
  EXPECT_DOUBLE_EQ(ssim(a, a), 1.0);
}
