// SPDX-License-Identifier: BSD-3-Clause
#include "afam/sampling/block_sampling.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <string>

#include "afam/base/cpu_features.hpp"
#include "afam/base/errors.hpp"

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

struct BlockTaps {
  AxisTaps tx, ty;
  int nx = 0, ny = 0;
  int64_t x0 = 0, x1 = 0;  ///< the columns of a plane the x taps read
  int64_t y0 = 0, y1 = 0;  ///< the rows of a plane the y taps read
};

/// acc[j * nx + i] += w * (the y-then-x filtered plane at block sample (i, j)) over its valid
/// samples: NaN samples (missing) are left out, and `weight` gathers the filter's weight of the
/// valid ones the same way; rows and rowWeights are scratch. The plane holds rows from yBase on.
template <typename T>
void addValidFilteredPlane(const T* plane, int64_t X, int64_t yBase, const BlockTaps& bt, double w,
                           std::vector<double>& rows, std::vector<double>& rowWeights,
                           std::vector<double>& acc, std::vector<double>& weight) {
  const AxisTaps &tx = bt.tx, &ty = bt.ty;
  const size_t width = size_t(bt.x1 - bt.x0 + 1);
  rows.assign(size_t(bt.ny) * width, 0.0);
  rowWeights.assign(size_t(bt.ny) * width, 0.0);
  for (int j = 0; j < bt.ny; ++j)
    for (size_t k = ty.first[size_t(j)]; k < ty.first[size_t(j) + 1]; ++k) {
      const T* src = plane + (ty.index[k] - yBase) * X + bt.x0;
      double* h = rows.data() + size_t(j) * width;
      double* hw = rowWeights.data() + size_t(j) * width;
      for (size_t c = 0; c < width; ++c)
        if (!std::isnan(double(src[c]))) {
          h[c] += ty.weight[k] * double(src[c]);
          hw[c] += ty.weight[k];
        }
    }
  for (int j = 0; j < bt.ny; ++j) {
    const size_t row = size_t(j) * width;
    for (int i = 0; i < bt.nx; ++i) {
      double v = 0, vw = 0;
      for (size_t k = tx.first[size_t(i)]; k < tx.first[size_t(i) + 1]; ++k) {
        v += tx.weight[k] * rows[row + size_t(tx.index[k] - bt.x0)];
        vw += tx.weight[k] * rowWeights[row + size_t(tx.index[k] - bt.x0)];
      }
      acc[size_t(j) * size_t(bt.nx) + size_t(i)] += w * v;
      weight[size_t(j) * size_t(bt.nx) + size_t(i)] += w * vw;
    }
  }
}

/// out[j * nx + i] = the y-then-x filtered plane at block sample (i, j); rows is scratch. y first:
/// it runs along whole rows of the columns the block reads (vectorised), and x then filters only
/// the block's rows. The plane holds rows from yBase on.
template <typename T>
__attribute__((always_inline)) inline void filterPlane(const T* plane, int64_t X, int64_t yBase,
                                                       const BlockTaps& bt,
                                                       std::vector<double>& rows, double* out) {
  const AxisTaps &tx = bt.tx, &ty = bt.ty;
  const size_t width = size_t(bt.x1 - bt.x0 + 1);
  rows.resize(size_t(bt.ny) * width);
  for (int j = 0; j < bt.ny; ++j) {
    double* __restrict h = rows.data() + size_t(j) * width;
    std::fill_n(h, width, 0.0);
    for (size_t k = ty.first[size_t(j)]; k < ty.first[size_t(j) + 1]; ++k) {
      const T* __restrict src = plane + (ty.index[k] - yBase) * X + bt.x0;
      const double wy = ty.weight[k];
      for (size_t c = 0; c < width; ++c) h[c] += wy * double(src[c]);
    }
  }
  for (int j = 0; j < bt.ny; ++j) {
    const double* h = rows.data() + size_t(j) * width - bt.x0;
    double* dst = out + size_t(j) * size_t(bt.nx);
    for (int i = 0; i < bt.nx; ++i) {
      double v = 0;
      for (size_t k = tx.first[size_t(i)]; k < tx.first[size_t(i) + 1]; ++k)
        v += tx.weight[k] * h[tx.index[k]];
      dst[i] = v;
    }
  }
}

/// The samples of a filtered z-sample that came out NaN (a missing sample among their taps) again,
/// from the valid samples alone: their weighted mean where they hold more than half of the
/// filter's weight, else missing (NaN). Samples with no missing tap keep their values.
template <typename T>
void refilterMissing(const std::function<const T*(size_t)>& planeOf, int64_t X, int64_t yBase,
                     const AxisTaps& tz, size_t t0, size_t t1, const BlockTaps& bt, float* dst) {
  const size_t nxy = size_t(bt.nx) * size_t(bt.ny);
  if (std::none_of(dst, dst + nxy, [](float v) { return std::isnan(v); })) return;
  std::vector<double> rows, rowWeights, acc(nxy, 0.0), weight(nxy, 0.0);
  for (size_t t = t0; t < t1; ++t)
    addValidFilteredPlane(planeOf(t), X, yBase, bt, tz.weight[t], rows, rowWeights, acc, weight);
  for (size_t q = 0; q < nxy; ++q)
    if (std::isnan(dst[q]))
      dst[q] = weight[q] > 0.5 ? static_cast<float>(acc[q] / weight[q])
                               : std::numeric_limits<float>::quiet_NaN();
}

/// The planes z-samples [k0, k1) need (ascending, distinct).
std::vector<int64_t> chunkPlanes(const AxisTaps& tz, int k0, int k1) {
  std::vector<int64_t> zs(tz.index.begin() + std::ptrdiff_t(tz.first[size_t(k0)]),
                          tz.index.begin() + std::ptrdiff_t(tz.first[size_t(k1)]));
  std::sort(zs.begin(), zs.end());
  zs.erase(std::unique(zs.begin(), zs.end()), zs.end());
  return zs;
}

/// How many planes of `plane` floats a chunk may hold: at most 256 MB, and with
/// ChunkBudget::QuarterOfSamples at most a quarter of the samples it fills (so a row of blocks and
/// the planes it is filtered from take at most 1.25 times the row's samples); at least one plane (a
/// chunk always covers one z-sample, whatever its taps).
size_t chunkPlaneBudget(size_t plane, const std::vector<std::vector<float>*>& out,
                        ChunkBudget budget) {
  size_t floats = (size_t(256) << 20) / sizeof(float);
  if (budget == ChunkBudget::QuarterOfSamples) {
    size_t samples = 0;
    for (const std::vector<float>* o : out) samples += o->size();
    floats = std::min(floats, samples / 4);
  }
  return std::max<size_t>(1, floats / plane);
}

/// Fills z-samples [k0, k1) of one block from a chunk's planes (zs[i] at buf + i * plane, rows from
/// yBase on).
template <typename T>
__attribute__((always_inline)) inline void fillBlockChunkBody(
    const T* buf, const std::vector<int64_t>& zs, size_t plane, int64_t X, int64_t yBase,
    const AxisTaps& tz, int k0, int k1, const BlockTaps& bt, float* out) {
  const size_t nxy = size_t(bt.nx) * size_t(bt.ny);
  const bool unitXY = bt.tx.unit && bt.ty.unit;
  // x taps at consecutive columns (a block's grid samples): rows are copied whole.
  bool xRun = true;
  for (size_t i = 1; i < bt.tx.index.size() && xRun; ++i)
    xRun = bt.tx.index[i] == bt.tx.index[0] + int64_t(i);
  std::vector<double> rows, acc;
  // The filtered planes of the last z-sample, kept for the next one (neighbouring z-samples share
  // the planes at their windows' ends): each plane of a chunk is filtered in x and y once.
  std::vector<int64_t> cachedZ, nextZ;
  std::vector<std::vector<double>> cached, next;
  const std::function<const T*(size_t)> planeOf = [&](size_t t) {
    const size_t i = size_t(std::lower_bound(zs.begin(), zs.end(), tz.index[t]) - zs.begin());
    return buf + i * plane;
  };
  for (int k = k0; k < k1; ++k) {
    float* dst = out + size_t(k) * nxy;
    const size_t t0 = tz.first[size_t(k)], t1 = tz.first[size_t(k) + 1];
    if (unitXY && t1 == t0 + 1 && tz.weight[t0] == 1.0) {  // grid samples: a copy
      const T* p = planeOf(t0);
      for (int j = 0; j < bt.ny; ++j) {
        const T* __restrict src = p + (bt.ty.index[size_t(j)] - yBase) * X;
        float* __restrict row = dst + size_t(j) * size_t(bt.nx);
        if (xRun) {
          src += bt.tx.index[0];
          for (int i = 0; i < bt.nx; ++i) row[i] = static_cast<float>(src[i]);
          continue;
        }
        for (int i = 0; i < bt.nx; ++i) row[i] = static_cast<float>(src[bt.tx.index[size_t(i)]]);
      }
      continue;
    }
    acc.assign(nxy, 0.0);
    nextZ.clear();
    for (size_t t = t0; t < t1; ++t) {
      const int64_t z = tz.index[t];
      size_t c = size_t(std::find(nextZ.begin(), nextZ.end(), z) - nextZ.begin());
      if (c == nextZ.size()) {  // not yet in this z-sample's planes: kept, or filtered now
        nextZ.push_back(z);
        if (next.size() < nextZ.size()) next.emplace_back();
        const size_t o = size_t(std::find(cachedZ.begin(), cachedZ.end(), z) - cachedZ.begin());
        if (o < cachedZ.size()) {
          std::swap(next[c], cached[o]);
          cachedZ[o] = -1;
        } else {
          next[c].resize(nxy);
          filterPlane(planeOf(t), X, yBase, bt, rows, next[c].data());
        }
      }
      const double w = tz.weight[t];
      const double* __restrict v = next[c].data();
      for (size_t q = 0; q < nxy; ++q) acc[q] += w * v[q];
    }
    std::swap(cachedZ, nextZ);
    std::swap(cached, next);
    for (size_t q = 0; q < nxy; ++q) dst[q] = static_cast<float>(acc[q]);
    refilterMissing<T>(planeOf, X, yBase, tz, t0, t1, bt, dst);
  }
}

// The filtering compiled also for AVX2 (its float-to-double rows convert in one instruction there)
// and chosen at run time; no FMA, so the same samples.
template <typename T>
AFAM_TARGET_AVX2 void fillBlockChunkAvx2(const T* buf, const std::vector<int64_t>& zs, size_t plane,
                                         int64_t X, int64_t yBase, const AxisTaps& tz, int k0,
                                         int k1, const BlockTaps& bt, float* out) {
  fillBlockChunkBody(buf, zs, plane, X, yBase, tz, k0, k1, bt, out);
}
template <typename T>
void fillBlockChunkOf(const T* buf, const std::vector<int64_t>& zs, size_t plane, int64_t X,
                      int64_t yBase, const AxisTaps& tz, int k0, int k1, const BlockTaps& bt,
                      float* out) {
  if (cpuHasAvx2())
    fillBlockChunkAvx2(buf, zs, plane, X, yBase, tz, k0, k1, bt, out);
  else
    fillBlockChunkBody(buf, zs, plane, X, yBase, tz, k0, k1, bt, out);
}
/// fillBlockChunk for a chunk in any of the types PlaneReader gives.
void fillBlockChunk(const PlaneChunk& chunk, const std::vector<int64_t>& zs, size_t plane,
                    int64_t X, int64_t yBase, const AxisTaps& tz, int k0, int k1,
                    const BlockTaps& bt, float* out) {
  const auto fill = [&](auto* typed) {  // typed: a null pointer of the chunk's sample type
    fillBlockChunkOf(static_cast<decltype(typed)>(chunk.samples), zs, plane, X, yBase, tz, k0, k1,
                     bt, out);
  };
  if (!isCopyType(chunk.type))
    throw Error("fillBlockChunk: planes of " + std::string(sampleTypeName(chunk.type)) +
                " samples (a source's storedType is 1- or 2-byte integers)");
  withCopyType(chunk.type, fill);
}

/// Pieces a chunk's filtering is split into at least (blocks times z-sample ranges) when it runs
/// on the sampling threads: enough for a few tens of threads to share a row of few blocks.
constexpr int64_t kFillPieces = 96;

}  // namespace

namespace {

/// Appends an axis' taps to a row's; returns where its entries of `first` start.
uint64_t appendTaps(const AxisTaps& t, RowTaps& row) {
  const uint64_t at = row.first.size(), base = row.index.size();
  for (size_t f : t.first) row.first.push_back(base + f);
  row.index.insert(row.index.end(), t.index.begin(), t.index.end());
  row.weight.insert(row.weight.end(), t.weight.begin(), t.weight.end());
  return at;
}

}  // namespace

RowTaps rowTaps(const Partition& part, int level, const std::vector<Int3>& blocks, bool ghost,
                LevelSampling sampling) {
  RowTaps row;
  if (blocks.empty()) return row;
  const int g = ghost ? 1 : 0;
  const BlockExtent ez = part.extent(level, blocks[0]);
  row.z = appendTaps(axisTaps(part, ez, level, 2, ghost, sampling), row);
  row.nz = ez.samples[2] + 2 * g;
  for (const Int3& b : blocks) {
    const BlockExtent e = part.extent(level, b);
    RowTaps::Block rb;
    rb.x = appendTaps(axisTaps(part, e, level, 0, ghost, sampling), row);
    rb.y = appendTaps(axisTaps(part, e, level, 1, ghost, sampling), row);
    rb.nx = e.samples[0] + 2 * g;
    rb.ny = e.samples[1] + 2 * g;
    row.blocks.push_back(rb);
  }
  return row;
}

PlaneReader::PlaneReader(VolumeSource& src, Index3 dims) : src_(src), rowSize_(dims[0]) {}

namespace {

/// Floats a piece of a parallel read holds at most (whole planes, at least one).
constexpr size_t kPieceFloats = size_t(1) << 20;

/// Runs of consecutive planes of zs as (first index in zs, planes), each at most `most` planes.
std::vector<std::pair<size_t, size_t>> planeRuns(const std::vector<int64_t>& zs, size_t most) {
  std::vector<std::pair<size_t, size_t>> runs;
  for (size_t i = 0; i < zs.size();) {
    size_t j = i + 1;
    while (j < zs.size() && j - i < most && zs[j] == zs[j - 1] + 1) ++j;
    runs.emplace_back(i, j - i);
    i = j;
  }
  return runs;
}

}  // namespace

PlaneChunk PlaneReader::read(const std::vector<int64_t>& zs, int64_t y0, int64_t yCount,
                             const BlockLoop& loop) {
  const size_t plane = size_t(rowSize_ * yCount);
  const std::optional<SampleType> stored = src_.storedType();
  const size_t bytes = stored ? size_t(sampleTypeSize(*stored)) : sizeof(float);
  growBuffer(buf_, (zs.size() * plane * bytes + sizeof(float) - 1) / sizeof(float));
  auto* buf = reinterpret_cast<unsigned char*>(buf_.data());
  const bool parallel = loop && src_.concurrentReads() && !src_.readsOnCallingThread();
  const auto runs = planeRuns(
      zs, parallel ? std::max<size_t>(1, kPieceFloats / std::max<size_t>(plane, 1)) : zs.size());
  auto readRun = [&](int64_t r) {
    const auto [i, n] = runs[size_t(r)];
    unsigned char* dst = buf + i * plane * bytes;
    if (stored)
      src_.readStoredRows(zs[i], int64_t(n), y0, yCount, dst);
    else
      src_.readRows(zs[i], int64_t(n), y0, yCount, reinterpret_cast<float*>(dst));
  };
  if (parallel && runs.size() > 1)
    loop(int64_t(runs.size()), readRun);
  else
    for (size_t r = 0; r < runs.size(); ++r) readRun(int64_t(r));
  bytesRead_ += zs.size() * plane * bytes;
  return PlaneChunk{buf, stored ? *stored : SampleType::Float32};
}

void sampleBlockRow(const Partition& part, PlaneReader& planes, int level,
                    const std::vector<Int3>& blocks, bool ghost, LevelSampling sampling,
                    std::vector<std::vector<float>*>& out, const BlockLoop& loop,
                    ChunkBudget budget) {
  if (blocks.empty()) return;
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
    const auto xs = std::minmax_element(taps[b].tx.index.begin(), taps[b].tx.index.end());
    taps[b].x0 = *xs.first;
    taps[b].x1 = *xs.second;
    const auto ys = std::minmax_element(taps[b].ty.index.begin(), taps[b].ty.index.end());
    taps[b].y0 = *ys.first;
    taps[b].y1 = *ys.second;
    const size_t count = size_t(taps[b].nx) * size_t(taps[b].ny) * size_t(nz);
    if (out[b]->capacity() < count) {  // every sample is written: nothing to copy over
      out[b]->clear();
      // An eighth more: a reused buffer then holds the level's other block sizes (one sample
      // more an axis), and growing to them fills only the new samples, not a new allocation.
      out[b]->reserve(count + count / 8);
    }
    out[b]->resize(count);
  }
  const int64_t X = part.dims()[0];
  int64_t yBase = taps[0].y0, yEnd = taps[0].y1;  // the rows the blocks read
  for (const BlockTaps& bt : taps) {
    yBase = std::min(yBase, bt.y0);
    yEnd = std::max(yEnd, bt.y1);
  }
  const size_t plane = size_t(X * (yEnd - yBase + 1));
  const size_t maxPlanes = chunkPlaneBudget(plane, out, budget);
  for (int k0 = 0; k0 < nz;) {
    int k1 = k0 + 1;  // the chunk grows while its planes fit the budget (at least one z-sample)
    while (k1 < nz && chunkPlanes(tz, k0, k1 + 1).size() <= maxPlanes) ++k1;
    const std::vector<int64_t> zs = chunkPlanes(tz, k0, k1);
    const PlaneChunk buf = planes.read(zs, yBase, yEnd - yBase + 1, loop);
    // Each block's z-samples in pieces, so that a row of few blocks (the coarse levels') still
    // spreads over the threads: at least kFillPieces pieces a chunk where it has the z-samples.
    const int64_t nb = int64_t(blocks.size()), span = k1 - k0;
    const int64_t pieces =
        loop ? std::min<int64_t>(span, std::max<int64_t>(1, (kFillPieces + nb - 1) / nb)) : 1;
    auto fill = [&](int64_t p) {
      const int64_t b = p % nb, piece = p / nb;
      const int ka = k0 + int(span * piece / pieces), kb = k0 + int(span * (piece + 1) / pieces);
      fillBlockChunk(buf, zs, plane, X, yBase, tz, ka, kb, taps[size_t(b)], out[size_t(b)]->data());
    };
    if (loop)
      loop(nb * pieces, fill);
    else
      for (int64_t b = 0; b < nb; ++b) fill(b);
    k0 = k1;
  }
}

std::vector<float> extractBlock(const Partition& part, const float* volume, int level, Int3 ijk,
                                bool ghost, LevelSampling sampling) {
  ArraySource src(volume, part.dims());
  PlaneReader planes(src, part.dims());
  std::vector<float> out;
  std::vector<std::vector<float>*> outs{&out};
  sampleBlockRow(part, planes, level, {ijk}, ghost, sampling, outs);
  return out;
}

struct BlockRowReader::Impl {
  Impl(VolumeSource& s, const Partition& p) : part(p), planes(s, p.dims()) {}
  const Partition& part;
  PlaneReader planes;
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
