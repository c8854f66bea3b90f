// SPDX-License-Identifier: BSD-3-Clause
#include "afam/volume/marschner_lobb.hpp"

#include <algorithm>
#include <sstream>
#include <thread>
#include <vector>

#include "afam/base/errors.hpp"

namespace afam {

namespace {
double coordinate(const MarschnerLobb& ml, int64_t k, int64_t n) {
  if (n <= 1) return 0.5 * (double(ml.lo) + double(ml.hi));
  return double(ml.lo) + (double(ml.hi) - double(ml.lo)) * double(k) / double(n - 1);
}
}  // namespace

void marschnerLobbSlab(const MarschnerLobb& ml, std::array<int64_t, 3> dims, int64_t z0,
                       int64_t zCount, float* out) {
  if (dims[0] < 1 || dims[1] < 1 || dims[2] < 1 || z0 < 0 || zCount < 0 || z0 + zCount > dims[2] ||
      (!out && zCount > 0) || !(ml.hi > ml.lo)) {
    std::ostringstream msg;
    msg << "afam marschnerLobbSlab: invalid slab [" << z0 << ", " << z0 + zCount << ") of "
        << dims[0] << " x " << dims[1] << " x " << dims[2] << " on [" << ml.lo << ", " << ml.hi
        << "]";
    throw InvalidArgument(msg.str());
  }
  const int64_t rows = dims[1] * zCount;
  std::vector<double> xs(static_cast<size_t>(dims[0]));
  for (int64_t i = 0; i < dims[0]; ++i) xs[size_t(i)] = coordinate(ml, i, dims[0]);
  auto work = [&](int64_t rowBegin, int64_t rowEnd) {
    for (int64_t row = rowBegin; row < rowEnd; ++row) {
      const int64_t j = row % dims[1], k = z0 + row / dims[1];
      const double y = coordinate(ml, j, dims[1]), z = coordinate(ml, k, dims[2]);
      float* dst = out + row * dims[0];
      for (int64_t i = 0; i < dims[0]; ++i) dst[i] = float(ml.valueT<double>(xs[size_t(i)], y, z));
    }
  };
  const int64_t samples = rows * dims[0];
  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  const int64_t threads = samples < (int64_t(1) << 20) ? 1 : std::min<int64_t>(hw, rows);
  if (threads <= 1) {
    work(0, rows);
    return;
  }
  std::vector<std::thread> pool;
  for (int64_t t = 0; t < threads; ++t)
    pool.emplace_back(work, rows * t / threads, rows * (t + 1) / threads);
  for (auto& th : pool) th.join();
}

}  // namespace afam
