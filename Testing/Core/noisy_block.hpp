// SPDX-License-Identifier: BSD-3-Clause
// Test helper: a block of smooth content plus Gaussian noise, for the least-squares tests (Core's
// and the GPU's).
#pragma once

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "afam/base/types.hpp"

namespace afam_test {

/// 100 + a smooth field of amplitude ~25, plus noise of deviation `noise`; n[0] x n[1] x n[2],
/// x fastest.
inline std::vector<float> smoothPlusNoise(afam::Int3 n, double noise, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0, noise);
  const size_t count = size_t(n[0]) * size_t(n[1]) * size_t(n[2]);
  std::vector<float> v(count);
  size_t i = 0;
  for (int z = 0; z < n[2]; ++z)
    for (int y = 0; y < n[1]; ++y)
      for (int x = 0; x < n[0]; ++x, ++i)
        v[i] = float(100 + 20 * std::sin(0.3 * x) * std::cos(0.2 * y) + 5 * std::sin(0.5 * z) +
                     normal(rng));
  return v;
}

}  // namespace afam_test
