// SPDX-License-Identifier: BSD-3-Clause
#include "afam/volume/reaction_diffusion.hpp"

#include <algorithm>
#include <random>
#include <string>
#include <thread>

#include "afam/base/errors.hpp"
#include "afam/base/worker_pool.hpp"

namespace afam {

GrayScott::GrayScott(const GrayScottOptions& options) : o_(options) {
  const Index3 d = o_.dims;
  if (d[0] < 3 || d[1] < 3 || d[2] < 3 || d[0] * d[1] * d[2] > (int64_t(1) << 31))
    throw InvalidArgument("simulate: dims must be >= 3 per axis and at most 2^31 samples");
  if (!(o_.du > 0 && o_.du <= 1.0 / 6) || !(o_.dv > 0 && o_.dv <= 1.0 / 6))
    throw InvalidArgument("simulate: diffusion rates must lie in (0, 1/6] (explicit stability)");
  if (o_.seeds < 1) throw InvalidArgument("simulate: at least one seed cube");
  const size_t n = size_t(d[0] * d[1] * d[2]);
  u_.assign(n, 1.0f);
  v_.assign(n, 0.0f);
  nu_.resize(n);
  nv_.resize(n);
  std::mt19937_64 rng(o_.seed);
  const int64_t half = std::max<int64_t>(1, std::min({d[0], d[1], d[2]}) / 16);
  for (int s = 0; s < o_.seeds; ++s) {
    int64_t c[3];
    for (int a = 0; a < 3; ++a) c[a] = int64_t(rng() % uint64_t(d[a]));
    for (int64_t z = c[2] - half; z <= c[2] + half; ++z)
      for (int64_t y = c[1] - half; y <= c[1] + half; ++y)
        for (int64_t x = c[0] - half; x <= c[0] + half; ++x) {
          const int64_t i =
              (((z + d[2]) % d[2]) * d[1] + (y + d[1]) % d[1]) * d[0] + (x + d[0]) % d[0];
          u_[size_t(i)] = 0.25f;
          v_[size_t(i)] = 0.5f;
        }
  }
}

void GrayScott::stepPlanes(int64_t z0, int64_t z1) {
  const Index3 d = o_.dims;
  const int64_t sy = d[0], sz = d[0] * d[1];
  const float du = float(o_.du), dv = float(o_.dv), f = float(o_.feed),
              fk = float(o_.feed + o_.kill);
  for (int64_t z = z0; z < z1; ++z) {
    const int64_t zm = (z + d[2] - 1) % d[2] * sz, zp = (z + 1) % d[2] * sz;
    for (int64_t y = 0; y < d[1]; ++y) {
      const int64_t ym = (y + d[1] - 1) % d[1] * sy, yp = (y + 1) % d[1] * sy;
      for (int64_t x = 0; x < d[0]; ++x) {
        const int64_t xm = (x + d[0] - 1) % d[0], xp = (x + 1) % d[0];
        const size_t i = size_t(z * sz + y * sy + x);
        const auto lap = [&](const std::vector<float>& q) {
          return q[size_t(z * sz + y * sy + xm)] + q[size_t(z * sz + y * sy + xp)] +
                 q[size_t(z * sz + ym + x)] + q[size_t(z * sz + yp + x)] +
                 q[size_t(zm + y * sy + x)] + q[size_t(zp + y * sy + x)] - 6 * q[i];
        };
        const float u = u_[i], v = v_[i], uvv = u * v * v;
        nu_[i] = u + du * lap(u_) - uvv + f * (1 - u);
        nv_[i] = v + dv * lap(v_) + uvv - fk * v;
      }
    }
  }
}

void GrayScott::advance(int iterations) {
  const Index3 d = o_.dims;
  // Each cell's update reads the last iteration only: planes are shared out to threads, and the
  // values are the same whatever their number. Small grids stay on one thread.
  int threads =
      o_.threads > 0 ? o_.threads : int(std::max(1u, std::thread::hardware_concurrency()));
  if (d[0] * d[1] * d[2] < (int64_t(1) << 20)) threads = 1;
  const int64_t chunks = std::min<int64_t>(d[2], int64_t(threads) * 4);
  WorkerPool pool(threads);
  for (int it = 0; it < iterations; ++it) {
    if (threads == 1) {
      stepPlanes(0, d[2]);
    } else {
      pool.run(
          chunks, [&](int, int64_t c) { stepPlanes(d[2] * c / chunks, d[2] * (c + 1) / chunks); },
          [] { return true; });
    }
    u_.swap(nu_);
    v_.swap(nv_);
  }
}

}  // namespace afam
