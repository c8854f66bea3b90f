// SPDX-License-Identifier: BSD-3-Clause
#include "hole_fill.hpp"

#include <algorithm>

namespace afam {

namespace {

/// Smoothing sweeps after the layers: the extension's creases between layers fade within a few
/// samples of the boundary, where the spline sees them.
constexpr int kSmoothingSweeps = 12;

struct Grid {
  Int3 n;
  int64_t sy, sz;
  explicit Grid(Int3 dims) : n(dims), sy(dims[0]), sz(int64_t(dims[0]) * dims[1]) {}
  int64_t count() const { return sz * n[2]; }
  /// Calls fn(j) for each face neighbour j of sample (x, y, z) at index i inside the block.
  template <typename Fn>
  void forNeighbours(int64_t i, Fn&& fn) const {
    const int x = int(i % n[0]), y = int((i / sy) % n[1]), z = int(i / sz);
    if (x > 0) fn(i - 1);
    if (x + 1 < n[0]) fn(i + 1);
    if (y > 0) fn(i - sy);
    if (y + 1 < n[1]) fn(i + sy);
    if (z > 0) fn(i - sz);
    if (z + 1 < n[2]) fn(i + sz);
  }
};

/// Mean of the known face neighbours of sample i (false when none is known).
bool meanOfKnown(const Grid& g, const float* v, const std::vector<uint8_t>& known, int64_t i,
                 float& out) {
  double sum = 0;
  int count = 0;
  g.forNeighbours(i, [&](int64_t j) {
    if (known[size_t(j)]) {
      sum += double(v[j]);
      ++count;
    }
  });
  if (count > 0) out = float(sum / count);
  return count > 0;
}

}  // namespace

void fillMissing(float* samples, Int3 n, const std::vector<uint32_t>& valid) {
  const Grid g(n);
  std::vector<uint8_t> known(size_t(g.count()));
  std::vector<int64_t> holes;
  for (int64_t i = 0; i < g.count(); ++i) {
    known[size_t(i)] = (valid[size_t(i >> 5)] >> (i & 31)) & 1u;
    if (!known[size_t(i)]) holes.push_back(i);
  }
  std::vector<int64_t> pending = holes, next, layer;
  std::vector<float> values;
  while (!pending.empty()) {  // one layer of holes beside known samples at a time
    layer.clear();
    values.clear();
    next.clear();
    for (int64_t i : pending) {
      float m;
      if (meanOfKnown(g, samples, known, i, m)) {
        layer.push_back(i);
        values.push_back(m);
      } else {
        next.push_back(i);
      }
    }
    if (layer.empty()) break;  // no valid sample at all: the caller's precondition
    for (size_t k = 0; k < layer.size(); ++k) {
      samples[layer[k]] = values[k];
      known[size_t(layer[k])] = 1;
    }
    pending.swap(next);
  }
  for (int sweep = 0; sweep < kSmoothingSweeps; ++sweep)
    for (int64_t i : holes) meanOfKnown(g, samples, known, i, samples[i]);
}

}  // namespace afam
