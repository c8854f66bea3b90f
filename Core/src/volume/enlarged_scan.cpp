// SPDX-License-Identifier: BSD-3-Clause
#include "afam/volume/enlarged_scan.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "afam/base/errors.hpp"

namespace afam {

namespace {

uint64_t mix(uint64_t x) {  // splitmix64's finaliser: a counter-based generator
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

/// Approximately standard normal, from four 16-bit uniforms of one hash (Irwin-Hall, |g| < 3.47).
float gaussianAt(uint64_t index, uint64_t seed) {
  const uint64_t h = mix(index ^ mix(seed));
  const float sum =
      float(h & 0xffff) + float((h >> 16) & 0xffff) + float((h >> 32) & 0xffff) + float(h >> 48);
  constexpr float kScale = 1.0f / 65536.0f;
  constexpr float kInvStd = 1.7320508f;  // 1 / sqrt(4 / 12)
  return (sum * kScale - 2.0f) * kInvStd;
}

float fade(float t) { return t * t * t * (t * (t * 6 - 15) + 10); }  // C2 from 0 to 1

/// Variance of a value-noise octave of spacing L along one axis (unit-variance lattice values),
/// averaged over the L positions of a cell: (1 - s)^2 + s^2.
double cellVariance(int64_t L) {
  double sum = 0;
  for (int64_t i = 0; i < L; ++i) {
    const double s = fade(float(i) / float(L));
    sum += (1 - s) * (1 - s) + s * s;
  }
  return sum / double(L);
}

float latticeValue(int64_t x, int64_t y, int64_t z, uint64_t key) {
  return gaussianAt(mix(mix(uint64_t(x) ^ key) ^ uint64_t(y)) ^ uint64_t(z), key);
}

/// The lattice of one octave interpolated between lattice planes iz and iz + 1 (fade sz).
void latticePlane(int64_t lx, int64_t ly, int64_t iz, float sz, uint64_t key, float* out) {
  for (int64_t j = 0; j < ly; ++j)
    for (int64_t i = 0; i < lx; ++i)
      out[size_t(j * lx + i)] =
          (1 - sz) * latticeValue(i, j, iz, key) + sz * latticeValue(i, j, iz + 1, key);
}

}  // namespace

double estimateScanNoise(const std::vector<float>& samples, const Index3& dims) {
  std::vector<float> diffs;
  for (int64_t row = 0; row < dims[1] * dims[2]; ++row)
    for (int64_t x = 0; x + 1 < dims[0]; ++x)
      diffs.push_back(
          std::fabs(samples[size_t(row * dims[0] + x + 1)] - samples[size_t(row * dims[0] + x)]));
  if (diffs.empty()) return 0;
  std::nth_element(diffs.begin(), diffs.begin() + std::ptrdiff_t(diffs.size() / 2), diffs.end());
  return double(diffs[diffs.size() / 2]) / (0.6745 * std::sqrt(2.0));
}

EnlargedScanSource::EnlargedScanSource(std::vector<float> samples, Index3 dims, Index3 target,
                                       double noiseSigma, uint64_t seed, double clampLo,
                                       double clampHi)
    : source_(std::move(samples)),
      dims_(dims),
      target_(target),
      sigma_(noiseSigma),
      seed_(seed),
      lo_(clampLo),
      hi_(clampHi),
      tissueSigma_(noiseSigma) {
  for (int a = 0; a < 3; ++a) {
    if (dims_[a] < 1) throw InvalidArgument("the volume to enlarge is empty");
    if (target_[a] < 2)
      throw InvalidArgument("an enlarged volume needs at least 2 samples per axis");
  }
  if (source_.size() != size_t(dims_[0] * dims_[1] * dims_[2]))
    throw InvalidArgument("the volume to enlarge has " + std::to_string(source_.size()) +
                          " samples, not the product of its dimensions");
  if (!(sigma_ >= 0) || !std::isfinite(sigma_))
    throw InvalidArgument("the noise must be finite and >= 0");
  tx_ = taps(dims_[0], target_[0]);
  ty_ = taps(dims_[1], target_[1]);
  tz_ = taps(dims_[2], target_[2]);
  const auto [smin, smax] = std::minmax_element(source_.begin(), source_.end());
  airEnd_ = *smin + kAirShare[0] * (*smax - *smin);
  tissueStart_ = *smin + kAirShare[1] * (*smax - *smin);
}

float EnlargedScanSource::tissueWeight(float v) const {
  if (!(tissueStart_ > airEnd_)) return 1.f;  // a constant source: no air to tell apart
  const float t = std::clamp((v - airEnd_) / (tissueStart_ - airEnd_), 0.f, 1.f);
  return t * t * (3 - 2 * t);
}

std::vector<EnlargedScanSource::Taps> EnlargedScanSource::taps(int64_t from, int64_t to) {
  std::vector<Taps> out(static_cast<size_t>(to));
  for (int64_t i = 0; i < to; ++i) {
    const double u = double(i) * double(from - 1) / double(to - 1);
    int64_t k = std::min<int64_t>(int64_t(std::floor(u)), std::max<int64_t>(from - 2, 0));
    const float t = float(u - double(k));
    Taps& tp = out[size_t(i)];
    float w[4] = {0.5f * (-t * t * t + 2 * t * t - t), 0.5f * (3 * t * t * t - 5 * t * t + 2),
                  0.5f * (-3 * t * t * t + 4 * t * t + t), 0.5f * (t * t * t - t * t)};
    // Ghost samples beyond the edges continue the edge linearly (p[-1] = 2 p[0] - p[1]), so that
    // a linear field stays linear up to the faces; a one-sample axis is constant.
    if (from == 1) {
      w[0] = 1;
      w[1] = w[2] = w[3] = 0;
    } else {
      if (k - 1 < 0) {  // tap 0 is p[-1]; taps 1 and 2 are p[0] and p[1]
        w[1] += 2 * w[0];
        w[2] -= w[0];
        w[0] = 0;
      }
      if (k + 2 > from - 1) {  // tap 3 is p[from]; taps 2 and 1 are p[from - 1] and p[from - 2]
        w[2] += 2 * w[3];
        w[1] -= w[3];
        w[3] = 0;
      }
    }
    for (int j = 0; j < 4; ++j) {
      tp.first[j] = std::clamp<int64_t>(k - 1 + j, 0, from - 1);
      tp.weight[j] = w[j];
    }
  }
  return out;
}

void EnlargedScanSource::setDetail(double sd, double beta) {
  if (!(sd >= 0) || !std::isfinite(sd)) throw InvalidArgument("the detail must be finite and >= 0");
  if (!(beta >= 0 && beta <= 3)) throw InvalidArgument("the detail's beta must be in [0, 3]");
  octaves_.clear();
  if (sd == 0) return;
  const int64_t largest = std::max({target_[0], target_[1], target_[2]});
  const int64_t top = std::min<int64_t>(128, std::max<int64_t>(2, largest / 4));
  double variance = 0;
  for (int64_t L = 2; L <= top; L *= 2) {
    const double a = std::pow(double(L), beta);
    octaves_.push_back({L, float(a)});
    variance += a * a * std::pow(cellVariance(L), 3);
  }
  const double scale = sd / std::sqrt(variance);
  for (Octave& o : octaves_) o.amplitude = float(double(o.amplitude) * scale);
}

void EnlargedScanSource::addDetail(int64_t z, float* dst) const {
  for (size_t k = 0; k < octaves_.size(); ++k)
    addOctave(octaves_[k], mix(mix(seed_ ^ 0xD37A11ED5EEDull) + k), z, dst);
}

void EnlargedScanSource::addOctave(const Octave& o, uint64_t key, int64_t z, float* dst) const {
  const int64_t L = o.spacing, nx = target_[0], ny = target_[1];
  const int64_t lx = (nx - 1) / L + 2, ly = (ny - 1) / L + 2, iz = z / L;
  std::vector<float> fades(static_cast<size_t>(L)), lattice(static_cast<size_t>(lx * ly)),
      row(static_cast<size_t>(lx));
  for (int64_t i = 0; i < L; ++i) fades[size_t(i)] = fade(float(i) / float(L));
  int shift = 0;
  while ((int64_t(1) << shift) < L) ++shift;
  latticePlane(lx, ly, iz, fades[size_t(z % L)], key, lattice.data());
  for (int64_t y = 0; y < ny; ++y) {
    const float sy = fades[size_t(y % L)];
    const float* a = lattice.data() + size_t((y / L) * lx);
    for (int64_t i = 0; i < lx; ++i)
      row[size_t(i)] = o.amplitude * ((1 - sy) * a[i] + sy * a[i + lx]);
    float* line = dst + size_t(y * nx);
    for (int64_t x = 0; x < nx; ++x) {  // L is a power of 2
      const float s = fades[size_t(x & (L - 1))];
      const size_t i = size_t(x >> shift);
      line[x] += (1 - s) * row[i] + s * row[i + 1];
    }
  }
}

const std::vector<float>& EnlargedScanSource::plane(int64_t z) {
  for (auto& p : planes_)
    if (p.first == z) return p.second;
  if (planes_.size() >= 4) planes_.erase(planes_.begin());  // planes are asked for in z order
  const int64_t nx = target_[0], ny = target_[1], sx = dims_[0], sy = dims_[1];
  std::vector<float> rows(size_t(nx * sy));  // x resampled, source rows
  const float* src = source_.data() + size_t(z * sx * sy);
  for (int64_t y = 0; y < sy; ++y)
    for (int64_t x = 0; x < nx; ++x) {
      const Taps& t = tx_[size_t(x)];
      float v = 0;
      for (int j = 0; j < 4; ++j) v += t.weight[j] * src[size_t(y * sx + t.first[j])];
      rows[size_t(y * nx + x)] = v;
    }
  std::vector<float> out(size_t(nx * ny), 0.f);
  for (int64_t y = 0; y < ny; ++y) {
    const Taps& t = ty_[size_t(y)];
    float* line = out.data() + size_t(y * nx);
    for (int j = 0; j < 4; ++j) {
      const float* r = rows.data() + size_t(t.first[j] * nx);
      for (int64_t x = 0; x < nx; ++x) line[x] += t.weight[j] * r[x];
    }
  }
  planes_.emplace_back(z, std::move(out));
  return planes_.back().second;
}

void EnlargedScanSource::readSlab(int64_t z0, int64_t zCount, float* out) {
  const int64_t nxy = target_[0] * target_[1];
  const float sigma = float(sigma_), lo = float(lo_), hi = float(hi_);
  for (int64_t z = z0; z < z0 + zCount; ++z) {
    const Taps& t = tz_[size_t(z)];
    float* dst = out + size_t((z - z0) * nxy);
    std::fill(dst, dst + nxy, 0.f);
    for (int j = 0; j < 4; ++j) {
      const std::vector<float>& p = plane(t.first[j]);
      for (int64_t i = 0; i < nxy; ++i) dst[i] += t.weight[j] * p[size_t(i)];
    }
    const bool tissueNoise = tissueSigma_ != sigma_;
    if (!octaves_.empty() || tissueNoise) {
      weight_.resize(size_t(nxy));
      for (int64_t i = 0; i < nxy; ++i) weight_[size_t(i)] = tissueWeight(dst[i]);
    }
    if (!octaves_.empty()) {
      detail_.assign(size_t(nxy), 0.f);
      addDetail(z, detail_.data());
      for (int64_t i = 0; i < nxy; ++i) dst[i] += weight_[size_t(i)] * detail_[size_t(i)];
    }
    const uint64_t base = uint64_t(z * nxy);
    const float extra = float(tissueSigma_ - sigma_);
    for (int64_t i = 0; i < nxy; ++i) {
      const float s = tissueNoise ? sigma + weight_[size_t(i)] * extra : sigma;
      const float v = s > 0 ? dst[i] + s * gaussianAt(base + uint64_t(i), seed_) : dst[i];
      dst[i] = std::clamp(v, lo, hi);
    }
  }
}

void EnlargedScanSource::setTissueNoise(double sd) {
  if (!(sd >= 0) || !std::isfinite(sd))
    throw InvalidArgument("the tissue noise must be finite and >= 0");
  tissueSigma_ = sd;
}

}  // namespace afam
