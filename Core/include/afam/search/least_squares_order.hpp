// SPDX-License-Identifier: BSD-3-Clause
// The arithmetic of a batched least-squares residual (least_squares_batch.hpp), written once for
// the CPU reference and the GPU kernel (host and device): every sum in the same order on both, so
// that they give the same doubles bit for bit. Sums over samples or outputs go to kLsqLanes lanes
// (element e to lane e % kLsqLanes, in increasing e: a GPU thread's share), then lsqTreeSum adds
// the lanes pairwise (as a block reduction in shared memory does).
#pragma once

#include <cstdint>

#include "afam/base/host_device.hpp"
#include "afam/base/types.hpp"

namespace afam {

constexpr int kLsqLanes = 256;

/// Sizes of one request's stages: a z-plane of samples, the plane after the x contraction
/// (ncp0 x n1), a z-slice after x and y (ncp0 x ncp1), and everything after y (n2 slices).
struct LsqShape {
  int64_t plane = 0, afterX = 0, slice = 0, afterY = 0;
};

AFAM_HD LsqShape lsqShape(Int3 n, Int3 k) {
  LsqShape s;
  s.plane = int64_t(n[0]) * n[1];
  s.afterX = int64_t(k[0]) * n[1];
  s.slice = int64_t(k[0]) * k[1];
  s.afterY = s.slice * n[2];
  return s;
}

/// Adds lanes[t + s] into lanes[t] for s = kLsqLanes/2 .. 1 and returns lanes[0] (changes lanes).
AFAM_HD double lsqTreeSum(double* lanes) {
  for (int s = kLsqLanes / 2; s > 0; s >>= 1)
    for (int t = 0; t < s; ++t) lanes[t] += lanes[t + s];
  return lanes[0];
}

/// Outputs o + r * step (r < R) of the x contraction of one centred plane (x fastest, rows of y
/// `planeStride` apart) into out[r]: output p = kx * n1 + y is the sum over x, in order, of
/// Qx[kx][x] * plane[y][x] (Qx: ncp0 x n0 rows). Outputs at or past `end` are computed as o and
/// left unused (R independent sums: a GPU thread's several outputs in flight at once).
template <int R>
AFAM_HD void lsqAlongX(const double* qx, const double* plane, int64_t planeStride, Int3 n,
                       int64_t o, int64_t step, int64_t end, double* out) {
  const double* row[R];
  const double* line[R];
  for (int r = 0; r < R; ++r) {
    const int64_t p = o + r * step < end ? o + r * step : o;
    row[r] = qx + (p / n[1]) * n[0];
    line[r] = plane + (p % n[1]) * planeStride;
    out[r] = 0;
  }
  for (int x = 0; x < n[0]; ++x)
    for (int r = 0; r < R; ++r) out[r] += row[r][x] * line[r][x];
}

/// Outputs o + r * step (r < R) of the y contraction of one plane after x (ncp0 x n1, y fastest)
/// into out[r]: output p = kx * ncp1 + ky is the sum over y, in order, of afterX[kx][y] *
/// Qy[ky][y] (Qy's rows `qyStride` apart). Outputs at or past `end` as in lsqAlongX.
template <int R>
AFAM_HD void lsqAlongY(const double* qy, int64_t qyStride, const double* afterX, Int3 n, Int3 k,
                       int64_t o, int64_t step, int64_t end, double* out) {
  const double* row[R];
  const double* line[R];
  for (int r = 0; r < R; ++r) {
    const int64_t p = o + r * step < end ? o + r * step : o;
    row[r] = qy + (p % k[1]) * qyStride;
    line[r] = afterX + (p / k[1]) * n[1];
    out[r] = 0;
  }
  for (int y = 0; y < n[1]; ++y)
    for (int r = 0; r < R; ++r) out[r] += line[r][y] * row[r][y];
}

/// The projection's energy on one column of the slices after y (its n2 values `stride` apart):
/// the sum over kz, in order, of (sum over z, in order, of Qz[kz][z] * column[z])^2; R rows of Qz
/// at a time.
template <int R>
AFAM_HD double lsqColumnEnergy(const double* qz, const double* column, int64_t stride, Int3 n,
                               Int3 k) {
  double energy = 0;
  for (int kz0 = 0; kz0 < k[2]; kz0 += R) {
    double sum[R];
    const double* row[R];
    for (int r = 0; r < R; ++r) {
      row[r] = qz + int64_t(kz0 + r < k[2] ? kz0 + r : kz0) * n[2];
      sum[r] = 0;
    }
    for (int z = 0; z < n[2]; ++z) {
      const double c = column[z * stride];
      for (int r = 0; r < R; ++r) sum[r] += row[r][z] * c;
    }
    for (int r = 0; r < R && kz0 + r < k[2]; ++r) energy += sum[r] * sum[r];
  }
  return energy;
}

}  // namespace afam
