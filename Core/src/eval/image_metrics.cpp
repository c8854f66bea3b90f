// SPDX-License-Identifier: BSD-3-Clause
#include "afam/eval/image_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "afam/base/errors.hpp"

namespace afam {
namespace {

void checkSame(const MetricImage& a, const MetricImage& b) {
  if (a.width != b.width || a.height != b.height)
    throw InvalidArgument("image metrics: sizes differ (" + std::to_string(a.width) + "x" +
                          std::to_string(a.height) + " vs " + std::to_string(b.width) + "x" +
                          std::to_string(b.height) + ")");
}

}  // namespace

MetricImage toMetricImage(const ImageRGB8& im) {
  MetricImage m;
  m.width = im.width;
  m.height = im.height;
  m.peak = 255.0;
  m.rgb.assign(im.rgb.begin(), im.rgb.end());
  return m;
}

MetricImage toMetricImage(const ImageRGBA& im) {
  MetricImage m;
  m.width = im.width;
  m.height = im.height;
  m.peak = 1.0;
  const size_t n = size_t(im.width) * size_t(im.height);
  m.rgb.resize(3 * n);
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) m.rgb[3 * i + c] = std::clamp(double(im.rgba[4 * i + c]), 0.0, 1.0);
  return m;
}

double mse(const MetricImage& a, const MetricImage& b) {
  checkSame(a, b);
  if (a.rgb.empty()) return 0.0;
  double s = 0;
  for (size_t i = 0; i < a.rgb.size(); ++i) {
    const double d = a.rgb[i] - b.rgb[i];
    s += d * d;
  }
  return s / double(a.rgb.size());
}

double psnr(const MetricImage& a, const MetricImage& b) {
  const double m = mse(a, b);
  if (m <= 0) return std::numeric_limits<double>::infinity();
  return 10.0 * std::log10(a.peak * a.peak / m);
}

double ssim(const MetricImage& a, const MetricImage& b) {
  checkSame(a, b);
  constexpr int R = 5;  // 11 x 11 window
  double w[2 * R + 1];
  double ws = 0;
  for (int i = -R; i <= R; ++i) ws += (w[i + R] = std::exp(-double(i * i) / (2 * 1.5 * 1.5)));
  for (double& x : w) x /= ws;
  const double L = a.peak, C1 = (0.01 * L) * (0.01 * L), C2 = (0.03 * L) * (0.03 * L);
  const int W = a.width, H = a.height;
  if (W < 2 * R + 1 || H < 2 * R + 1) {
    // Too small for the window: one global window.
    double total = 0;
    for (int c = 0; c < 3; ++c) {
      double ma = 0, mb = 0, n = double(W) * H;
      for (int i = 0; i < W * H; ++i) ma += a.rgb[3 * i + c], mb += b.rgb[3 * i + c];
      ma /= n, mb /= n;
      double va = 0, vb = 0, cab = 0;
      for (int i = 0; i < W * H; ++i) {
        const double da = a.rgb[3 * i + c] - ma, db = b.rgb[3 * i + c] - mb;
        va += da * da, vb += db * db, cab += da * db;
      }
      va /= n, vb /= n, cab /= n;
      total += ((2 * ma * mb + C1) * (2 * cab + C2)) / ((ma * ma + mb * mb + C1) * (va + vb + C2));
    }
    return total / 3;
  }
  // Separable Gaussian filtering of a, b, a^2, b^2, ab (horizontal then vertical, valid region).
  const int ow = W - 2 * R, oh = H - 2 * R;
  double total = 0;
  std::vector<double> tmp(size_t(5) * W * oh);
  for (int c = 0; c < 3; ++c) {
    auto A = [&](int x, int y) { return a.rgb[3 * (size_t(y) * W + x) + c]; };
    auto B = [&](int x, int y) { return b.rgb[3 * (size_t(y) * W + x) + c]; };
    // vertical pass into tmp (oh rows x W columns x 5 moments)
    for (int y = 0; y < oh; ++y)
      for (int x = 0; x < W; ++x) {
        double m[5] = {0, 0, 0, 0, 0};
        for (int k = 0; k <= 2 * R; ++k) {
          const double va = A(x, y + k), vb = B(x, y + k), g = w[k];
          m[0] += g * va, m[1] += g * vb, m[2] += g * va * va, m[3] += g * vb * vb,
              m[4] += g * va * vb;
        }
        for (int q = 0; q < 5; ++q) tmp[(size_t(q) * oh + y) * W + x] = m[q];
      }
    double sum = 0;
    for (int y = 0; y < oh; ++y)
      for (int x = 0; x < ow; ++x) {
        double m[5] = {0, 0, 0, 0, 0};
        for (int k = 0; k <= 2 * R; ++k)
          for (int q = 0; q < 5; ++q) m[q] += w[k] * tmp[(size_t(q) * oh + y) * W + x + k];
        const double ma = m[0], mb = m[1];
        const double va = m[2] - ma * ma, vb = m[3] - mb * mb, cab = m[4] - ma * mb;
        sum += ((2 * ma * mb + C1) * (2 * cab + C2)) / ((ma * ma + mb * mb + C1) * (va + vb + C2));
      }
    total += sum / (double(ow) * oh);
  }
  return total / 3;
}

ImageErrors compare(const MetricImage& test, const MetricImage& ref) {
  ImageErrors e;
  e.mse = mse(test, ref);
  e.psnr = e.mse > 0 ? 10.0 * std::log10(ref.peak * ref.peak / e.mse) : 99.0;
  e.ssim = ssim(test, ref);
  return e;
}

ImageErrors compare(const ImageRGB8& test, const ImageRGB8& ref) {
  return compare(toMetricImage(test), toMetricImage(ref));
}

}  // namespace afam
