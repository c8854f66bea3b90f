// SPDX-License-Identifier: BSD-3-Clause
#include "afam/block_sampling.hpp"

#include <algorithm>
#include <cmath>

namespace afam {

namespace {

/// The taps of one axis: sample s is sum_k weight[k] * v[index[k]] for k in [first[s], first[s+1]).
struct AxisTaps {
  std::vector<int64_t> index;
  std::vector<double> weight;
  std::vector<size_t> first{0};
  bool unit = true;  ///< every sample is one tap of weight 1 (a grid sample)
  void close() { first.push_back(index.size()); }
  void add(int64_t i, double w) {
    if (w == 0) return;
    if (!index.empty() && first.back() < index.size() && index.back() == i) {
      weight.back() += w;
      return;
    }
    index.push_back(i);
    weight.push_back(w);
  }
};

/// Linear interpolation at pos (clamped to [0, dim - 1]).
void addPointTaps(double pos, int64_t dim, AxisTaps& t) {
  pos = std::min(std::max(pos, 0.0), double(dim - 1));
  int64_t i0 = static_cast<int64_t>(std::floor(pos));
  double w = pos - double(i0);
  if (w < 1e-12) w = 0;
  if (w > 1 - 1e-12) {
    ++i0;
    w = 0;
  }
  i0 = std::min(i0, dim - 1);
  t.add(i0, 1 - w);
  if (w != 0) t.add(std::min(i0 + 1, dim - 1), w);
  t.close();
  if (w != 0) t.unit = false;
}

/// Adds scale x the integral of the axis' linear interpolant over [a, b] (0 <= a < b <= dim - 1):
/// per unit interval the trapezoid rule is exact for a linear function.
void addIntegral(double a, double b, double scale, AxisTaps& t) {
  for (int64_t i = int64_t(std::floor(a)); double(i) < b; ++i) {
    const double s = std::max(a, double(i)) - double(i), e = std::min(b, double(i + 1)) - double(i);
    if (e <= s) continue;
    const double len = (e - s) * scale, mid = 0.5 * (s + e);  // the interpolant's mean is at mid
    t.add(i, len * (1 - mid));
    t.add(i + 1, len * mid);
  }
}

/// Mean of the interpolant over a window of `width` centred on pos, the volume mirrored at its
/// ends (the filtered field stays smooth up to the boundary; a shifted window would freeze it there
/// and leave a kink that splines pay for); the whole axis when the window is longer than it.
void addBoxTaps(double pos, double width, int64_t dim, AxisTaps& t) {
  const double last = double(dim - 1);
  if (width >= last) {
    addIntegral(0, last, 1 / last, t);
  } else {
    const double lo = pos - 0.5 * width, hi = pos + 0.5 * width;
    addIntegral(std::max(lo, 0.0), std::min(hi, last), 1 / width, t);
    if (lo < 0) addIntegral(0, -lo, 1 / width, t);
    if (hi > last) addIntegral(2 * last - hi, last, 1 / width, t);
  }
  t.close();
  t.unit = false;
}

AxisTaps axisTaps(const Partition& part, const BlockExtent& e, int level, int axis, bool ghost,
                  LevelSampling sampling) {
  const int64_t dim = part.dims()[axis];
  const int n = e.samples[axis];
  const int g = ghost ? 1 : 0;
  const int r = part.stride(level);
  const bool box = sampling == LevelSampling::Box && r > 1 && dim > 1;
  AxisTaps t;
  const double step = n > 1 ? double(e.hi[axis] - e.lo[axis]) / double(n - 1) : 0.0;
  for (int k = -g; k < n + g; ++k) {
    double pos;
    if (k < 0)
      pos = double(e.lo[axis]) - step;
    else if (k >= n)
      pos = double(e.hi[axis]) + step;
    else
      pos = part.samplePosition(e, axis, k);
    if (!box) {
      addPointTaps(pos, dim, t);
      continue;
    }
    addBoxTaps(std::min(std::max(pos, 0.0), double(dim - 1)), double(r), dim, t);
  }
  if (t.first.size() != t.index.size() + 1) t.unit = false;
  return t;
}

/// One output sample from a (filtered) plane: sum over the y and x taps.
template <typename T>
double sampleXY(const T* plane, int64_t X, const AxisTaps& tx, size_t i, const AxisTaps& ty, size_t j) {
  double v = 0;
  for (size_t ky = ty.first[j]; ky < ty.first[j + 1]; ++ky) {
    const T* row = plane + ty.index[ky] * X;
    double h = 0;
    for (size_t kx = tx.first[i]; kx < tx.first[i + 1]; ++kx) h += tx.weight[kx] * double(row[tx.index[kx]]);
    v += ty.weight[ky] * h;
  }
  return v;
}

struct BlockTaps {
  AxisTaps tx, ty;
  int nx = 0, ny = 0;
};

template <typename T>
void fillPlaneSamples(const T* plane, int64_t X, const BlockTaps& bt, float* dst) {
  for (int j = 0; j < bt.ny; ++j) {
    float* row = dst + size_t(j) * size_t(bt.nx);
    if (bt.tx.unit && bt.ty.unit) {
      const T* src = plane + bt.ty.index[size_t(j)] * X;
      for (int i = 0; i < bt.nx; ++i) row[i] = static_cast<float>(src[bt.tx.index[size_t(i)]]);
      continue;
    }
    for (int i = 0; i < bt.nx; ++i) row[i] = static_cast<float>(sampleXY(plane, X, bt.tx, size_t(i), bt.ty, size_t(j)));
  }
}

}  // namespace

PlaneCache::PlaneCache(VolumeSource& src, Index3 dims) : src_(src), plane_(size_t(dims[0] * dims[1])) {}

const float* PlaneCache::get(int64_t z) {
  for (auto& s : slot_)
    if (s.z == z) {
      s.used = ++tick_;
      return s.data.data();
    }
  Slot& s = slot_[0].used <= slot_[1].used ? slot_[0] : slot_[1];
  s.data.resize(plane_);
  src_.readSlab(z, 1, s.data.data());
  bytesRead_ += plane_ * sizeof(float);
  s.z = z;
  s.used = ++tick_;
  return s.data.data();
}

void sampleBlockRow(const Partition& part, PlaneCache& planes, int level, const std::vector<Int3>& blocks,
                    bool ghost, LevelSampling sampling, std::vector<std::vector<float>*>& out) {
  if (blocks.empty()) return;
  const Index3 dims = part.dims();
  const int g = ghost ? 1 : 0;
  std::vector<BlockTaps> taps(blocks.size());
  const BlockExtent ez = part.extent(level, blocks[0]);
  const AxisTaps tz = axisTaps(part, ez, level, 2, ghost, sampling);
  const int nz = ez.samples[2] + 2 * g;
  for (size_t b = 0; b < blocks.size(); ++b) {
    const BlockExtent e = part.extent(level, blocks[b]);
    taps[b].tx = axisTaps(part, e, level, 0, ghost, sampling);
    taps[b].ty = axisTaps(part, e, level, 1, ghost, sampling);
    taps[b].nx = e.samples[0] + 2 * g;
    taps[b].ny = e.samples[1] + 2 * g;
    out[b]->resize(size_t(taps[b].nx) * size_t(taps[b].ny) * size_t(nz));
  }
  const int64_t X = dims[0];
  const size_t plane = size_t(dims[0] * dims[1]);
  std::vector<double> acc;  // the z-filtered plane when a z-sample has more than one tap
  for (int k = 0; k < nz; ++k) {
    const size_t k0 = tz.first[size_t(k)], k1 = tz.first[size_t(k) + 1];
    const bool single = k1 == k0 + 1 && tz.weight[k0] == 1.0;
    if (!single) {
      acc.assign(plane, 0.0);
      for (size_t t = k0; t < k1; ++t) {
        const float* p = planes.get(tz.index[t]);
        const double w = tz.weight[t];
        for (size_t q = 0; q < plane; ++q) acc[q] += w * double(p[q]);
      }
    }
    const float* p0 = single ? planes.get(tz.index[k0]) : nullptr;
    for (size_t b = 0; b < blocks.size(); ++b) {
      float* dst = out[b]->data() + size_t(k) * size_t(taps[b].nx) * size_t(taps[b].ny);
      if (single)
        fillPlaneSamples(p0, X, taps[b], dst);
      else
        fillPlaneSamples(acc.data(), X, taps[b], dst);
    }
  }
}

std::vector<float> extractBlock(const Partition& part, const float* volume, int level, Int3 ijk, bool ghost,
                                LevelSampling sampling) {
  ArraySource src(volume, part.dims());
  PlaneCache planes(src, part.dims());
  std::vector<float> out;
  std::vector<std::vector<float>*> outs{&out};
  sampleBlockRow(part, planes, level, {ijk}, ghost, sampling, outs);
  return out;
}

struct BlockRowReader::Impl {
  Impl(VolumeSource& s, const Partition& p) : part(p), planes(s, p.dims()) {}
  const Partition& part;
  PlaneCache planes;
};

BlockRowReader::BlockRowReader(VolumeSource& source, const Partition& partition)
    : impl_(std::make_unique<Impl>(source, partition)) {}
BlockRowReader::~BlockRowReader() = default;
uint64_t BlockRowReader::bytesRead() const { return impl_->planes.bytesRead(); }

void BlockRowReader::readRow(int level, int kz, bool ghost, LevelSampling sampling,
                             std::vector<std::vector<float>>& out) {
  const Int3 nb = impl_->part.blocksPerAxis(level);
  std::vector<Int3> row;
  for (int j = 0; j < nb[1]; ++j)
    for (int i = 0; i < nb[0]; ++i) row.push_back({i, j, kz});
  out.resize(row.size());
  std::vector<std::vector<float>*> outs(row.size());
  for (size_t r = 0; r < row.size(); ++r) outs[r] = &out[r];
  sampleBlockRow(impl_->part, impl_->planes, level, row, ghost, sampling, outs);
}

}  // namespace afam
