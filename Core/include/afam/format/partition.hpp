// SPDX-License-Identifier: BSD-3-Clause
// Multi-resolution partition of a volume into micro-blocks: the one place that decides which
// samples each micro-block holds. Encoder, file reader, LOD selection and ray casters all ask it.
//
// Level numbering (also in docs/FORMAT.md): level 0 is the coarsest, level L-1 the finest.
// Per axis with N samples, the finest level has Bf = min(B, max(1, N-1)) blocks whose boundaries
// are the sample indices round(i (N-1) / Bf), i = 0..Bf, so neighbours share one boundary sample.
// Level l groups r = 2^(L-1-l) finest blocks per axis: it has ceil(Bf / r) blocks (the last one may
// group fewer; that is how edge blocks of any dims are handled) and block j spans the finest
// boundaries [j r, min((j+1) r, Bf)]. Its micro-block is sampled with stride r: n =
// round(extent/r)+1 samples at lo + k (hi-lo)/(n-1). Where those positions fall between grid
// samples (dims that are not B 2^k + 1) the value is linearly interpolated along that axis; for B
// 2^k + 1 dims every position is a grid sample and the micro-block is the paper's plain strided
// downsampling. A one-sample axis gives blocks of extent 0 with n = 1.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace afam {

using Int3 = std::array<int, 3>;
using Index3 = std::array<int64_t, 3>;

/// The finest block edge, in samples, of the default partition: the paper's 16 blocks at 1024^3,
/// and on the corpus (32-93 samples an axis) the smallest files of the edges tried (16, 32, 64; see
/// docs/BENCHMARKS.md, "Compression against ZFP").
constexpr int kDefaultBlockEdge = 64;

/// Levels and finest blocks per axis that fit a volume: blocks of about kDefaultBlockEdge samples
/// along the longest axis (B = round((N - 1) / edge), at least 1), and levels down to a coarsest
/// level of 2 blocks along it (L = 1 + floor(log2(B / 2)); 1 when B < 4). For 1025^3 and the
/// default edge of 64 that is the paper's 16 blocks and 4 levels.
struct PartitionShape {
  int levels = 1, blocksPerAxis = 1;
};
PartitionShape defaultPartition(const Index3& dims, int blockEdge = kDefaultBlockEdge);

/// How the samples of a coarse level (stride r > 1) are taken from the volume. Point: the sampling
/// rule above (linear interpolation at the sample positions), the paper's strided downsampling.
/// Box: the mean of the volume's (multi)linear interpolant over a window of r samples per axis
/// centred on each position (the volume mirrored at its ends; the whole axis when it is shorter),
/// i.e. the volume filtered for the level's spacing, so that coarse levels do not alias. The finest
/// level (r = 1) is point-sampled either way.
enum class LevelSampling : uint8_t { Point = 0, Box = 1 };

/// Where one micro-block sits, in voxel index coordinates of the full volume.
struct BlockExtent {
  Index3 lo{};     ///< first sample index per axis
  Index3 hi{};     ///< last sample index per axis (shared with the next block)
  Int3 samples{};  ///< micro-block samples per axis
};

/// A box of finest blocks (a rank's share of the volume, ranks/rank_boxes.hpp): cells [lo, hi)
/// per axis (finest block indices). Empty when any axis has hi <= lo.
struct CellBox {
  Int3 lo{0, 0, 0}, hi{0, 0, 0};
  bool empty() const { return hi[0] <= lo[0] || hi[1] <= lo[1] || hi[2] <= lo[2]; }
  int64_t cells() const {
    return empty() ? 0 : int64_t(hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
  }
  bool contains(const Int3& c) const {
    for (int a = 0; a < 3; ++a)
      if (c[a] < lo[a] || c[a] >= hi[a]) return false;
    return true;
  }
  /// The cells both boxes hold (empty when they do not meet).
  CellBox intersection(const CellBox& o) const {
    CellBox both;
    for (int a = 0; a < 3; ++a) {
      both.lo[a] = lo[a] > o.lo[a] ? lo[a] : o.lo[a];
      both.hi[a] = hi[a] < o.hi[a] ? hi[a] : o.hi[a];
    }
    return both;
  }
  bool operator==(const CellBox& o) const { return lo == o.lo && hi == o.hi; }
};

class Partition {
 public:
  Partition() = default;
  /// Throws afam::InvalidArgument on dims < 1, levels outside [1, 16], blocks < 1.
  Partition(Index3 dims, int levels, int finestBlocksPerAxis);

  const Index3& dims() const { return dims_; }
  int levels() const { return levels_; }
  int requestedBlocks() const { return requestedBlocks_; }
  /// Blocks per axis at a level.
  Int3 blocksPerAxis(int level) const;
  int64_t blockCount(int level) const;
  int64_t totalBlockCount() const;
  /// Sampling stride (in finest samples) of a level: 2^(levels-1-level).
  int stride(int level) const { return 1 << (levels_ - 1 - level); }
  BlockExtent extent(int level, Int3 ijk) const;
  /// Linear index of a block inside its level, x fastest.
  int64_t linearIndex(int level, Int3 ijk) const;
  Int3 blockFromLinear(int level, int64_t index) const;
  /// Children at level+1 of a block (1 to 8 of them), as ijk.
  std::vector<Int3> children(int level, Int3 ijk) const;
  Int3 parent(int level, Int3 ijk) const;  ///< block at level-1 holding this one
  /// The finest blocks (cells) a block of `level` covers.
  CellBox cells(int level, Int3 ijk) const;
  /// The samples a box of finest blocks spans, [lo, hi] per axis (boxes that meet share their
  /// boundary samples, as blocks do): what a rank's box covers in the volume's index space.
  /// An empty box spans nothing (lo = hi = 0). Throws afam::InvalidArgument for a box that
  /// reaches outside the finest blocks.
  BlockExtent samples(const CellBox& box) const;

  /// How every message names a block: "level 2 block (3, 0, 7)".
  static std::string blockName(int level, Int3 ijk);

  /// Sample positions (voxel index coordinate, possibly fractional) of a micro-block on one axis.
  double samplePosition(const BlockExtent& e, int axis, int k) const;

 private:
  Index3 dims_{1, 1, 1};
  int levels_ = 1;
  int requestedBlocks_ = 1;
  std::array<std::vector<int64_t>, 3> finestBounds_;  // Bf+1 boundaries per axis
};

}  // namespace afam
