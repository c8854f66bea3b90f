// SPDX-License-Identifier: BSD-3-Clause
#include "afam/scene/transfer_function.hpp"

#include <algorithm>
#include <cmath>

#include "afam/base/errors.hpp"

namespace afam {
namespace {

template <typename P, typename F>
double interp(std::vector<P> pts, double x, F get) {
  if (pts.empty()) return 0.0;
  std::sort(pts.begin(), pts.end(), [](const P& a, const P& b) { return a.value < b.value; });
  if (x <= pts.front().value) return get(pts.front());
  if (x >= pts.back().value) return get(pts.back());
  for (size_t i = 1; i < pts.size(); ++i) {
    if (x <= pts[i].value) {
      const double d = pts[i].value - pts[i - 1].value;
      const double w = d > 0 ? (x - pts[i - 1].value) / d : 1.0;
      return get(pts[i - 1]) + w * (get(pts[i]) - get(pts[i - 1]));
    }
  }
  return get(pts.back());
}

}  // namespace

double TransferFunction::opacity(double v) const {
  return interp(opacities, v, [](const OpacityPoint& p) { return p.alpha; });
}

void TransferFunction::color(double v, double rgb[3]) const {
  if (colors.empty()) {
    rgb[0] = rgb[1] = rgb[2] = 1.0;
    return;
  }
  rgb[0] = interp(colors, v, [](const ColorPoint& p) { return p.r; });
  rgb[1] = interp(colors, v, [](const ColorPoint& p) { return p.g; });
  rgb[2] = interp(colors, v, [](const ColorPoint& p) { return p.b; });
}

namespace {

/// Entry i of `out` (n entries over [lo, hi]) from the sampled table of `tf` (linear between its
/// entries, its end entries outside its range).
void resampleEntry(const TransferFunction& tf, double v, float* out) {
  const size_t m = tf.sampled.size() / 4;
  const double span = tf.sampledHi - tf.sampledLo;
  double x = span > 0 ? (v - tf.sampledLo) / span * double(m - 1) : 0.0;
  x = std::clamp(x, 0.0, double(m - 1));
  const size_t i = std::min(size_t(x), m > 1 ? m - 2 : 0);
  const double w = m > 1 ? x - double(i) : 0.0;
  const float* e0 = tf.sampled.data() + 4 * i;
  const float* e1 = m > 1 ? e0 + 4 : e0;
  for (int c = 0; c < 4; ++c) out[c] = float(double(e0[c]) + w * double(e1[c] - e0[c]));
  out[3] = std::clamp(out[3], 0.f, 1.f);
}

}  // namespace

std::vector<float> TransferFunction::table(int n, double lo, double hi) const {
  if (n < 2) throw InvalidArgument("transfer function: table size must be >= 2");
  std::vector<float> t(size_t(4) * size_t(n));
  const bool fromSampled = sampled.size() >= 4;
  for (int i = 0; i < n; ++i) {
    const double v = lo + (hi - lo) * double(i) / double(n - 1);
    if (fromSampled) {
      resampleEntry(*this, v, &t[4 * size_t(i)]);
      continue;
    }
    double rgb[3];
    color(v, rgb);
    t[4 * i + 0] = float(rgb[0]);
    t[4 * i + 1] = float(rgb[1]);
    t[4 * i + 2] = float(rgb[2]);
    t[4 * i + 3] = float(std::clamp(opacity(v), 0.0, 1.0));
  }
  return t;
}

float TransferFunction::maxOpacity(const std::vector<float>& table, double lo, double hi,
                                   double vmin, double vmax) {
  const int n = int(table.size() / 4);
  if (n == 0) return 0.f;
  auto index = [&](double v) {
    const double r = hi - lo;
    double t = r > 0 ? (v - lo) / r : 0.0;
    t = std::clamp(t, 0.0, 1.0) * double(n - 1);
    return t;
  };
  if (!(vmin <= vmax)) std::swap(vmin, vmax);
  const int i0 = std::max(0, int(std::floor(index(vmin))));
  const int i1 = std::min(n - 1, int(std::ceil(index(vmax))));
  float m = 0.f;
  for (int i = i0; i <= i1; ++i) m = std::max(m, table[4 * size_t(i) + 3]);
  return m;
}

TransferFunction TransferFunction::preset(double lo, double hi) {
  TransferFunction tf;
  const double r = hi - lo;
  auto at = [&](double f) { return lo + f * r; };
  tf.colors = {{at(0.0), 0.10, 0.20, 0.90},
               {at(0.25), 0.15, 0.45, 1.00},
               {at(0.5), 0.20, 0.90, 0.35},
               {at(0.75), 1.00, 0.55, 0.10},
               {at(1.0), 0.90, 0.10, 0.10}};
  tf.opacities = {{at(0.0), 0.0}, {at(0.15), 0.0},  {at(0.2), 0.0},  {at(0.25), 0.015},
                  {at(0.3), 0.0}, {at(0.45), 0.0},  {at(0.5), 0.03}, {at(0.55), 0.0},
                  {at(0.7), 0.0}, {at(0.75), 0.12}, {at(0.8), 0.0},  {at(1.0), 0.0}};
  tf.referenceDistance = 0.01;
  return tf;
}

}  // namespace afam
