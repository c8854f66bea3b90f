// SPDX-License-Identifier: BSD-3-Clause
#include "afam/sampling/level_sampler.hpp"

#include <cstring>

#include "afam/base/errors.hpp"

namespace afam {

bool levelSamplerHolds(SampleType type) { return isCopyType(type); }

bool CpuLevelSampler::reserve(Index3 dims, SampleType type, std::string& why) {
  if (!levelSamplerHolds(type)) {
    why = std::string("it holds 1- and 2-byte integers and float32, not ") + sampleTypeName(type);
    return false;
  }
  dims_ = dims;
  type_ = type;
  volume_.assign(size_t(dims[0] * dims[1] * dims[2]) * size_t(sampleTypeSize(type)), 0);
  return true;
}

void CpuLevelSampler::load(int64_t z0, int64_t nz, const void* samples) {
  const size_t plane = size_t(dims_[0] * dims_[1]) * size_t(sampleTypeSize(type_));
  if (z0 < 0 || nz < 0 || z0 + nz > dims_[2])
    throw InvalidArgument("CpuLevelSampler: planes [" + std::to_string(z0) + ", " +
                          std::to_string(z0 + nz) + ") outside the volume's " +
                          std::to_string(dims_[2]));
  std::memcpy(volume_.data() + size_t(z0) * plane, samples, size_t(nz) * plane);
}

namespace {

template <typename T>
void filterBlock(const T* volume, const Index3& dims, const RowTaps& taps, size_t b, float* out) {
  const RowTaps::Block& rb = taps.blocks[b];
  const AxisTapsView tx = taps.view(rb.x), ty = taps.view(rb.y), tz = taps.view(taps.z);
  for (int k = 0; k < taps.nz; ++k)
    for (int j = 0; j < rb.ny; ++j)
      for (int i = 0; i < rb.nx; ++i)
        *out++ = filteredSample(volume, dims[0], dims[0] * dims[1], tx, ty, tz, i, j, k);
}

}  // namespace

void CpuLevelSampler::sampleRow(const Partition& part, int level, const std::vector<Int3>& blocks,
                                bool ghost, LevelSampling sampling,
                                std::vector<std::vector<float>*>& out, const BlockLoop& loop) {
  const RowTaps taps = rowTaps(part, level, blocks, ghost, sampling);
  auto fill = [&](int64_t b) {
    std::vector<float>& o = *out[size_t(b)];
    o.resize(taps.samples(size_t(b)));
    withCopyType(type_, [&](auto* typed) {
      filterBlock(static_cast<decltype(typed)>(static_cast<const void*>(volume_.data())), dims_,
                  taps, size_t(b), o.data());
    });
  };
  if (loop)
    loop(int64_t(blocks.size()), fill);
  else
    for (size_t b = 0; b < blocks.size(); ++b) fill(int64_t(b));
}

namespace {

template <typename T>
void boxOf(const T* volume, const Index3& dims, const Index3& origin, const Int3& n, float* out) {
  const int64_t count = int64_t(n[0]) * n[1] * n[2];
  for (int64_t s = 0; s < count; ++s)
    out[s] = boxSample(volume, dims[0], dims[0] * dims[1], origin, n, s);
}

}  // namespace

void CpuLevelSampler::box(const Index3& origin, const Int3& n, float* out) const {
  for (int a = 0; a < 3; ++a)
    if (origin[a] < 0 || n[a] < 0 || origin[a] + n[a] > dims_[a])
      throw InvalidArgument("CpuLevelSampler: a box of " + std::to_string(n[a]) + " samples from " +
                            std::to_string(origin[a]) + " outside the copy's " +
                            std::to_string(dims_[a]) + " along axis " + std::to_string(a));
  withCopyType(type_, [&](auto* typed) {
    boxOf(static_cast<decltype(typed)>(static_cast<const void*>(volume_.data())), dims_, origin, n,
          out);
  });
}

void CpuLevelSampler::release() {
  volume_.clear();
  volume_.shrink_to_fit();
}

}  // namespace afam
