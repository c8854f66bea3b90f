// SPDX-License-Identifier: BSD-3-Clause
#include "afam/volume/masked_volumes.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "afam/base/errors.hpp"

namespace afam {

namespace {

constexpr double kSeaLevel = 0.55;    ///< Land: relief above it is land at every depth
constexpr double kShelfStart = 0.25;  ///< the sea floor rises from relief 0.25 to the coast
constexpr int kReliefBumps = 24;

/// Relief in [0, 1] over the xy-plane: a sum of Gaussian bumps of random places, widths and signs,
/// rescaled to [0, 1].
std::vector<float> makeRelief(Index3 dims, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  struct Bump {
    double x, y, width, height;
  };
  std::vector<Bump> bumps;
  for (int k = 0; k < kReliefBumps; ++k)
    bumps.push_back({unit(rng), unit(rng), 0.06 + 0.18 * unit(rng), unit(rng) < 0.7 ? 1.0 : -0.6});
  const int64_t nx = dims[0], ny = dims[1];
  std::vector<float> relief(size_t(nx * ny));
  for (int64_t y = 0; y < ny; ++y)
    for (int64_t x = 0; x < nx; ++x) {
      const double u = nx > 1 ? double(x) / double(nx - 1) : 0.5;
      const double v = ny > 1 ? double(y) / double(ny - 1) : 0.5;
      double h = 0;
      for (const Bump& b : bumps) {
        const double d2 = (u - b.x) * (u - b.x) + (v - b.y) * (v - b.y);
        h += b.height * std::exp(-d2 / (2 * b.width * b.width));
      }
      relief[size_t(y * nx + x)] = float(h);
    }
  const auto mm = std::minmax_element(relief.begin(), relief.end());
  const float lo = *mm.first, span = std::max(*mm.second - lo, 1e-6f);
  for (float& h : relief) h = (h - lo) / span;
  return relief;
}

double fraction(int64_t i, int64_t n) { return n > 1 ? double(i) / double(n - 1) : 0.5; }

}  // namespace

MaskShape parseMaskShape(const std::string& name) {
  if (name == "ball") return MaskShape::Ball;
  if (name == "fov") return MaskShape::FieldOfView;
  if (name == "land") return MaskShape::Land;
  throw InvalidArgument("mask shape '" + name + "' is not ball, fov or land");
}

VolumeMask::VolumeMask(MaskShape shape, Index3 dims, uint64_t seed) : shape_(shape), dims_(dims) {
  if (shape == MaskShape::Land) relief_ = makeRelief(dims, seed);
}

bool VolumeMask::missing(int64_t x, int64_t y, int64_t z) const {
  switch (shape_) {
    case MaskShape::Ball: {
      const double r = 0.25 * double(std::min({dims_[0], dims_[1], dims_[2]}) - 1);  // in samples
      const double dx = double(x) - 0.5 * double(dims_[0] - 1),
                   dy = double(y) - 0.5 * double(dims_[1] - 1),
                   dz = double(z) - 0.5 * double(dims_[2] - 1);
      return dx * dx + dy * dy + dz * dz <= r * r;
    }
    case MaskShape::FieldOfView: {
      const double r = 0.5 * double(std::min(dims_[0], dims_[1]) - 1);
      const double dx = double(x) - 0.5 * double(dims_[0] - 1),
                   dy = double(y) - 0.5 * double(dims_[1] - 1);
      return dx * dx + dy * dy > r * r;
    }
    case MaskShape::Land: {
      const double h = relief_[size_t(y * dims_[0] + x)];
      if (h >= kSeaLevel) return true;                                     // land
      const double floor = (h - kShelfStart) / (kSeaLevel - kShelfStart);  // 0 deep .. 1 coast
      return fraction(z, dims_[2]) < floor;  // z = 0 the deepest plane
    }
  }
  return false;
}

MaskedSource::MaskedSource(VolumeSource& inner, const VolumeMask& mask, float fill)
    : WrappingSource(inner), mask_(mask), fill_(fill) {}

void MaskedSource::readSlab(int64_t z0, int64_t zCount, float* out) {
  inner_.readSlab(z0, zCount, out);
  const Index3 d = dims();
  size_t i = 0;
  for (int64_t z = z0; z < z0 + zCount; ++z)
    for (int64_t y = 0; y < d[1]; ++y)
      for (int64_t x = 0; x < d[0]; ++x, ++i)
        if (mask_.missing(x, y, z)) out[i] = fill_;
}

void fillNearestValid(std::vector<float>& v, Index3 dims) {
  const int64_t sy = dims[0], sz = dims[0] * dims[1], n = sz * dims[2];
  std::vector<int64_t> front, next;
  std::vector<uint8_t> known(static_cast<size_t>(n), 0);
  for (int64_t i = 0; i < n; ++i) {
    known[size_t(i)] = std::isnan(v[size_t(i)]) ? 0 : 1;
    if (known[size_t(i)]) front.push_back(i);
  }
  if (front.empty()) throw InvalidArgument("nearest-value fill: no sample is valid");
  while (!front.empty()) {
    next.clear();
    for (int64_t i : front) {
      const int64_t x = i % sy, y = (i / sy) % dims[1], z = i / sz;
      const int64_t nb[6] = {x > 0 ? i - 1 : -1,  x + 1 < dims[0] ? i + 1 : -1,
                             y > 0 ? i - sy : -1, y + 1 < dims[1] ? i + sy : -1,
                             z > 0 ? i - sz : -1, z + 1 < dims[2] ? i + sz : -1};
      for (int64_t j : nb)
        if (j >= 0 && !known[size_t(j)]) {
          known[size_t(j)] = 1;
          v[size_t(j)] = v[size_t(i)];
          next.push_back(j);
        }
    }
    front.swap(next);
  }
}

}  // namespace afam
