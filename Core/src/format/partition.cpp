// SPDX-License-Identifier: BSD-3-Clause
#include "afam/format/partition.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "afam/base/errors.hpp"

namespace afam {

Partition::Partition(Index3 dims, int levels, int finestBlocksPerAxis)
    : dims_(dims), levels_(levels), requestedBlocks_(finestBlocksPerAxis) {
  for (int a = 0; a < 3; ++a) {
    if (dims[a] < 1)
      throw InvalidArgument(std::string("partition: axis ") + "xyz"[a] + " has " +
                            std::to_string(dims[a]) + " samples; every axis needs at least 1");
  }
  if (levels < 1 || levels > 16)
    throw InvalidArgument("partition: levels is " + std::to_string(levels) +
                          ", must be in [1, 16]");
  if (finestBlocksPerAxis < 1 || finestBlocksPerAxis > 65535)
    throw InvalidArgument("partition: blocks per axis is " + std::to_string(finestBlocksPerAxis) +
                          ", must be in [1, 65535]");
  for (int a = 0; a < 3; ++a) {
    const int64_t n = dims[a];
    const int64_t bf = std::min<int64_t>(finestBlocksPerAxis, std::max<int64_t>(1, n - 1));
    auto& b = finestBounds_[a];
    b.resize(static_cast<size_t>(bf + 1));
    for (int64_t i = 0; i <= bf; ++i)
      b[static_cast<size_t>(i)] = static_cast<int64_t>(std::llround(
          static_cast<double>(i) * static_cast<double>(n - 1) / static_cast<double>(bf)));
  }
}

Int3 Partition::blocksPerAxis(int level) const {
  const int64_t r = stride(level);
  Int3 out{};
  for (int a = 0; a < 3; ++a) {
    const int64_t bf = static_cast<int64_t>(finestBounds_[a].size()) - 1;
    out[a] = static_cast<int>((bf + r - 1) / r);
  }
  return out;
}

int64_t Partition::blockCount(int level) const {
  const Int3 b = blocksPerAxis(level);
  return int64_t(b[0]) * b[1] * b[2];
}

int64_t Partition::totalBlockCount() const {
  int64_t total = 0;
  for (int l = 0; l < levels_; ++l) total += blockCount(l);
  return total;
}

BlockExtent Partition::extent(int level, Int3 ijk) const {
  const Int3 b = blocksPerAxis(level);
  const int64_t r = stride(level);
  BlockExtent e;
  for (int a = 0; a < 3; ++a) {
    if (ijk[a] < 0 || ijk[a] >= b[a])
      throw InvalidArgument("partition: block index " + std::to_string(ijk[a]) + " on axis " +
                            std::to_string(a) + " outside [0, " + std::to_string(b[a]) +
                            ") at level " + std::to_string(level));
    const auto& fb = finestBounds_[a];
    const int64_t bf = static_cast<int64_t>(fb.size()) - 1;
    const int64_t first = ijk[a] * r;
    const int64_t last = std::min<int64_t>((ijk[a] + 1) * r, bf);
    e.lo[a] = fb[static_cast<size_t>(first)];
    e.hi[a] = fb[static_cast<size_t>(last)];
    const int64_t extentSamples = e.hi[a] - e.lo[a];
    if (extentSamples == 0) {
      e.samples[a] = 1;
    } else {
      const int64_t n =
          std::llround(static_cast<double>(extentSamples) / static_cast<double>(r)) + 1;
      e.samples[a] = static_cast<int>(std::max<int64_t>(2, n));
    }
  }
  return e;
}

double Partition::samplePosition(const BlockExtent& e, int axis, int k) const {
  const int n = e.samples[axis];
  if (n <= 1) return static_cast<double>(e.lo[axis]);
  if (k == n - 1) return static_cast<double>(e.hi[axis]);  // exact shared boundary
  return static_cast<double>(e.lo[axis]) +
         static_cast<double>(k) * static_cast<double>(e.hi[axis] - e.lo[axis]) / (n - 1);
}

int64_t Partition::linearIndex(int level, Int3 ijk) const {
  const Int3 b = blocksPerAxis(level);
  return (int64_t(ijk[2]) * b[1] + ijk[1]) * b[0] + ijk[0];
}

Int3 Partition::blockFromLinear(int level, int64_t index) const {
  const Int3 b = blocksPerAxis(level);
  Int3 ijk{};
  ijk[0] = static_cast<int>(index % b[0]);
  ijk[1] = static_cast<int>((index / b[0]) % b[1]);
  ijk[2] = static_cast<int>(index / (int64_t(b[0]) * b[1]));
  return ijk;
}

std::vector<Int3> Partition::children(int level, Int3 ijk) const {
  std::vector<Int3> out;
  if (level + 1 >= levels_) return out;
  const Int3 b = blocksPerAxis(level + 1);
  for (int z = 2 * ijk[2]; z < std::min(2 * ijk[2] + 2, b[2]); ++z)
    for (int y = 2 * ijk[1]; y < std::min(2 * ijk[1] + 2, b[1]); ++y)
      for (int x = 2 * ijk[0]; x < std::min(2 * ijk[0] + 2, b[0]); ++x) out.push_back({x, y, z});
  return out;
}

Int3 Partition::parent(int level, Int3 ijk) const {
  (void)level;
  return {ijk[0] / 2, ijk[1] / 2, ijk[2] / 2};
}

CellBox Partition::cells(int level, Int3 ijk) const {
  const int r = stride(level);
  CellBox box;
  for (int a = 0; a < 3; ++a) {
    const int finest = static_cast<int>(finestBounds_[a].size()) - 1;
    box.lo[a] = ijk[a] * r;
    box.hi[a] = std::min((ijk[a] + 1) * r, finest);
  }
  return box;
}

BlockExtent Partition::samples(const CellBox& box) const {
  BlockExtent e;
  if (box.empty()) return e;
  for (int a = 0; a < 3; ++a) {
    const auto& fb = finestBounds_[a];
    const int finest = static_cast<int>(fb.size()) - 1;
    if (box.lo[a] < 0 || box.hi[a] > finest)
      throw InvalidArgument("partition: cells " + std::to_string(box.lo[a]) + ".." +
                            std::to_string(box.hi[a]) + " on axis " + std::to_string(a) +
                            " outside the " + std::to_string(finest) + " finest blocks");
    e.lo[a] = fb[static_cast<size_t>(box.lo[a])];
    e.hi[a] = fb[static_cast<size_t>(box.hi[a])];
    e.samples[a] = static_cast<int>(e.hi[a] - e.lo[a] + 1);
  }
  return e;
}

PartitionShape defaultPartition(const Index3& dims, int blockEdge) {
  if (blockEdge < 2)
    throw InvalidArgument("block edge " + std::to_string(blockEdge) + " must be >= 2 samples");
  const int64_t n = std::max({dims[0], dims[1], dims[2]});
  PartitionShape s;
  s.blocksPerAxis =
      int(std::max<int64_t>(1, std::min<int64_t>(65535, std::llround(double(n - 1) / blockEdge))));
  while (s.levels < 16 && (s.blocksPerAxis >> s.levels) >= 2) ++s.levels;
  return s;
}

std::string Partition::blockName(int level, Int3 ijk) {
  return "level " + std::to_string(level) + " block (" + std::to_string(ijk[0]) + ", " +
         std::to_string(ijk[1]) + ", " + std::to_string(ijk[2]) + ")";
}

}  // namespace afam
