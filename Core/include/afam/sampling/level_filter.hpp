// SPDX-License-Identifier: BSD-3-Clause
// One block sample of a level filtered from the whole volume, written once for the CPU reference
// (CpuLevelSampler) and the GPU (afam/cuda/encode/make_gpu_level_sampler.hpp), host and device:
// the sums of sampleBlockRow (block_sampling.hpp) in its order, so that the floats are its floats
// bit for bit. sampleBlockRow filters each plane along y (per column: the sum over the y taps,
// from 0), then along x (the sum over the x taps of those columns, from 0), and adds the planes
// along z (the sum over the z taps, from 0), in double, products and sums rounded apart (no fused
// multiply-add: the device code is compiled with -fmad=false).
#pragma once

#include <cstdint>

#include "afam/base/host_device.hpp"

namespace afam {

/// The taps of one axis of one block: sample s is the sum over t in [first[s], first[s + 1]) of
/// weight[t] * v[index[t]] (pointers into a row's flattened taps, RowTaps).
struct AxisTapsView {
  const int64_t* index = nullptr;
  const double* weight = nullptr;
  const uint64_t* first = nullptr;
};

/// Sample (i, j, k) of a block whose axes' taps are tx, ty, tz, filtered from `volume` (x fastest,
/// rows `rowSize` samples apart, planes `planeSize`; T the type it is stored in).
template <typename T>
AFAM_HD float filteredSample(const T* volume, int64_t rowSize, int64_t planeSize,
                             const AxisTapsView& tx, const AxisTapsView& ty, const AxisTapsView& tz,
                             int i, int j, int k) {
  double acc = 0;
  for (uint64_t t = tz.first[k]; t < tz.first[k + 1]; ++t) {
    const T* plane = volume + tz.index[t] * planeSize;
    double v = 0;
    for (uint64_t a = tx.first[i]; a < tx.first[i + 1]; ++a) {
      const T* column = plane + tx.index[a];
      double h = 0;
      for (uint64_t b = ty.first[j]; b < ty.first[j + 1]; ++b)
        h += ty.weight[b] * double(column[ty.index[b] * rowSize]);
      v += tx.weight[a] * h;
    }
    acc += tz.weight[t] * v;
  }
  return static_cast<float>(acc);
}

/// Sample s (x fastest) of the box of n samples from `origin` of `volume` (rows `rowSize` samples
/// apart, planes `planeSize`): the volume's own sample, as the finest level's block holds it.
template <typename T>
AFAM_HD float boxSample(const T* volume, int64_t rowSize, int64_t planeSize, const Index3& origin,
                        const Int3& n, int64_t s) {
  const int64_t plane = int64_t(n[0]) * n[1];
  const int64_t k = s / plane, j = (s % plane) / n[0], i = s % n[0];
  return static_cast<float>(
      volume[(origin[2] + k) * planeSize + (origin[1] + j) * rowSize + origin[0] + i]);
}

}  // namespace afam
