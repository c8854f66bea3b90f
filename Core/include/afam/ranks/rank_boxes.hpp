// SPDX-License-Identifier: BSD-3-Clause
// Which part of the volume each of N ranks draws (sort-last rendering): one convex box of finest
// blocks per rank, from a k-d split of the finest block grid, the same on every rank because it is
// computed from the file's index alone (no communication, no camera).
//
// Work of a finest block, from the index (cellWork): the bytes a view reads and decodes for it,
// its stored payload and its share of its coarser ancestors' (each ancestor's bytes divided among
// the finest blocks it covers: a view that draws a coarser level there reads those), over the
// mean of the blocks that count. Bytes, not voxels: what a rank reads is what its cache, loads
// and GPU uploads cost, and a smooth region of few bytes is cheap to cast too (measured over the
// recorded paths user_1 and user_2 on the head MRI made 301x370x316 with --detail 18, 128^2,
// screen LOD: every rank of 2, 3 and 4 read at most 0.52, 0.42 and 0.29 of one rank's bytes;
// weighing voxels and bytes half each, one rank of 4 read 0.335 on user_1). Blocks that count
// nothing: empty blocks (no valid sample; rays skip
// them) and blocks constant at the file's lowest value (a scan's air: transparent under any
// transfer function that hides the lowest value, and culled then). Every block also gets a floor
// of 1e-3 (of a mean block's work), so that a box of air is still split by its size.
//
// The split (splitCells): a box with more than one rank is cut by the plane, on a finest block
// boundary of any axis, that minimises the larger per-rank work of its two sides (the ranks shared
// between the sides in proportion to their work, each side given no more ranks than blocks).
// Among planes within 5% of that best, one on the boundary of a coarser level is preferred (the
// coarsest), so that fewer coarse blocks are read by two ranks. Ties go to the longer axis in
// voxels, then the lower axis, then the lower plane. Deterministic: the same integers and doubles
// in the same order on every rank.
//
// Any N >= 1 works. With N at least the number of finest blocks, every finest block is a box of
// its own and the ranks beyond them get empty boxes (CellBox::empty(); they draw nothing and
// their images are transparent). A block of a coarser level that spans several boxes is drawn by
// each of their ranks within its own box only (clipFrameToBox, render/prepared_frame.hpp).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "afam/format/afam_file.hpp"
#include "afam/format/partition.hpp"
#include "afam/scene/ray_camera.hpp"

namespace afam {

/// Ranks a split accepts at most: far more than any machine runs, small enough that a mistake
/// (a negative number read as unsigned, a byte count) is refused.
constexpr int kMaxRanks = 1 << 20;

/// The finest block grid a split works on: cells per axis, each cell's work (x fastest) and its
/// boundaries in voxels (cells + 1 per axis, for the axis lengths and coarse-level alignment).
struct CellGrid {
  Int3 cells{1, 1, 1};
  std::vector<double> work;
  std::array<std::vector<int64_t>, 3> bounds;
  int levels = 1;  ///< levels of the file: a plane at index s lies on level l's boundaries when
                   ///< s is a multiple of 2^(levels-1-l)
};

/// The file's finest block grid with each block's work (see the header comment).
CellGrid cellWork(const AfamFile& file);

/// The k-d split of `grid` among `ranks` ranks and its tree (for visibility order).
class RankSplit {
 public:
  /// Throws InvalidArgument for ranks < 1 or > kMaxRanks, or a grid whose work does not match its
  /// cells or holds a negative or non-finite value.
  RankSplit(const CellGrid& grid, int ranks);
  /// The split of a file's finest blocks (cellWork).
  static RankSplit ofFile(const AfamFile& file, int ranks) { return {cellWork(file), ranks}; }

  /// Box of rank r (empty for ranks beyond the finest blocks).
  const std::vector<CellBox>& boxes() const { return boxes_; }
  /// Work of each rank's box (the sum of its cells' work).
  const std::vector<double>& work() const { return work_; }
  /// The ranks front to back as seen from a camera (perspective: from its eye; parallel: along
  /// its forward direction), the volume being [boxLo, boxHi] in the camera's frame and `dims`
  /// samples per axis: composited in this order, the boxes' images are the image of one. Ranks
  /// with empty boxes come last.
  std::vector<int> visibilityOrder(const RayCamera& camera, const float* boxLo, const float* boxHi,
                                   const Index3& dims) const;

 private:
  struct Node {
    int axis = -1;      ///< -1: a leaf
    int64_t plane = 0;  ///< the cut, in voxels
    int low = -1, high = -1;
    int rank = -1;  ///< a leaf's rank
  };
  int build(const CellGrid& grid, const CellBox& box, int firstRank, int ranks);
  void visit(int node, const std::vector<char>& lowFirst, std::vector<int>& order) const;

  std::vector<CellBox> boxes_;
  std::vector<double> work_;
  std::vector<Node> nodes_;
};

/// Rank `rank`'s box among `ranks` (RankSplit::ofFile), what its Renderer draws
/// (RendererResources::box). Throws InvalidArgument, naming both numbers, when rank is not one of
/// 0 .. ranks-1 (a run whose ranks disagree on how many they are), and as RankSplit does.
CellBox rankBox(const AfamFile& file, int rank, int ranks);

}  // namespace afam
