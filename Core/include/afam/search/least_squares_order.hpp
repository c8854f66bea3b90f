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

/// Output o = kx * n1 + y of the x contraction of one centred plane (x fastest, rows of y
/// `planeStride` apart): sum over x of Qx[kx][x] * plane[y][x]. Qx: ncp0 x n0 rows.
AFAM_HD double lsqAlongX(const double* qx, const double* plane, int64_t planeStride, Int3 n,
                         int64_t o) {
  const int64_t kx = o / n[1], y = o % n[1];
  const double* row = qx + kx * n[0];
  const double* line = plane + y * planeStride;
  double sum = 0;
  for (int x = 0; x < n[0]; ++x) sum += row[x] * line[x];
  return sum;
}

/// Output o = kx * ncp1 + ky of the y contraction of one plane after x (ncp0 x n1, y fastest):
/// sum over y of afterX[kx][y] * Qy[ky][y] (Qy's rows `qyStride` apart).
AFAM_HD double lsqAlongY(const double* qy, int64_t qyStride, const double* afterX, Int3 n, Int3 k,
                         int64_t o) {
  const int64_t kx = o / k[1], ky = o % k[1];
  const double* row = qy + ky * qyStride;
  const double* line = afterX + kx * n[1];
  double sum = 0;
  for (int y = 0; y < n[1]; ++y) sum += line[y] * row[y];
  return sum;
}

/// The projection's energy on one column of the slices after y (its n2 values `stride` apart):
/// the sum over kz of (sum over z of Qz[kz][z] * column[z])^2.
AFAM_HD double lsqColumnEnergy(const double* qz, const double* column, int64_t stride, Int3 n,
                               Int3 k) {
  double energy = 0;
  for (int kz = 0; kz < k[2]; ++kz) {
    const double* row = qz + int64_t(kz) * n[2];
    double sum = 0;
    for (int z = 0; z < n[2]; ++z) sum += row[z] * column[z * stride];
    energy += sum * sum;
  }
  return energy;
}

}  // namespace afam
