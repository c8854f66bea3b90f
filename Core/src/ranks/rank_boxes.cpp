// SPDX-License-Identifier: BSD-3-Clause
#include "afam/ranks/rank_boxes.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "afam/base/errors.hpp"

namespace afam {

namespace {

constexpr double kWorkFloor = 1e-3;           ///< of a mean block's work, for every block
constexpr double kAlignmentTolerance = 0.05;  ///< a coarser-level plane may cost this much more

size_t cellIndex(const Int3& cells, int x, int y, int z) {
  return (size_t(z) * size_t(cells[1]) + size_t(y)) * size_t(cells[0]) + size_t(x);
}

/// Whether a block's bytes count (header comment): not empty, not all at the lowest value.
bool countsWork(const AfamFile& file, const ModelEntry& e) {
  return e.kind != BlockKind::Empty && e.maxValue > float(file.header().valueMin);
}

/// Each slab's work along each axis of `box` (slab i: the cells of index lo[a] + i on axis a).
std::array<std::vector<double>, 3> slabWork(const CellGrid& g, const CellBox& box) {
  std::array<std::vector<double>, 3> slabs;
  for (int a = 0; a < 3; ++a) slabs[a].assign(size_t(box.hi[a] - box.lo[a]), 0.0);
  for (int z = box.lo[2]; z < box.hi[2]; ++z)
    for (int y = box.lo[1]; y < box.hi[1]; ++y)
      for (int x = box.lo[0]; x < box.hi[0]; ++x) {
        const double w = g.work[cellIndex(g.cells, x, y, z)];
        slabs[0][size_t(x - box.lo[0])] += w;
        slabs[1][size_t(y - box.lo[1])] += w;
        slabs[2][size_t(z - box.lo[2])] += w;
      }
  return slabs;
}

/// A candidate cut: at cell index `plane` of `axis`, `lowRanks` ranks on the low side; cost is
/// the larger per-rank work of the two sides.
struct Cut {
  int axis = -1;
  int plane = 0;
  int lowRanks = 0;
  double cost = 0;
  int alignment = 0;  ///< levels above the finest whose boundaries hold the plane
  int64_t axisVoxels = 0;
};

/// How many of `ranks` go low (each side at least one rank and at most one a cell) and the cost.
void shareRanks(double low, double high, int ranks, int64_t lowCells, int64_t highCells, Cut& c) {
  const int least = int(std::max<int64_t>(1, ranks - highCells));
  const int most = int(std::min<int64_t>(ranks - 1, lowCells));
  const double ideal = double(ranks) * low / (low + high);
  c.cost = -1;
  for (int k : {int(std::floor(ideal)), int(std::ceil(ideal))}) {
    k = std::clamp(k, least, most);
    const double cost = std::max(low / k, high / (ranks - k));
    if (c.cost < 0 || cost < c.cost) {
      c.cost = cost;
      c.lowRanks = k;
    }
  }
}

int alignmentOf(const CellGrid& g, int plane) {
  int level = 0;
  while (level + 1 < g.levels && plane % (1 << (level + 1)) == 0) ++level;
  return level;
}

/// Whether a is the better of two cuts within the tolerance (header comment's order).
bool better(const Cut& a, const Cut& b) {
  if (a.alignment != b.alignment) return a.alignment > b.alignment;
  if (a.cost != b.cost) return a.cost < b.cost;
  if (a.axisVoxels != b.axisVoxels) return a.axisVoxels > b.axisVoxels;
  if (a.axis != b.axis) return a.axis < b.axis;
  return a.plane < b.plane;
}

std::vector<Cut> candidateCuts(const CellGrid& g, const CellBox& box, int ranks) {
  const auto slabs = slabWork(g, box);
  std::vector<Cut> cuts;
  for (int a = 0; a < 3; ++a) {
    const int64_t cross = box.cells() / (box.hi[a] - box.lo[a]);
    double total = 0;
    for (double w : slabs[size_t(a)]) total += w;
    double low = 0;
    for (int s = box.lo[a] + 1; s < box.hi[a]; ++s) {
      low += slabs[size_t(a)][size_t(s - 1 - box.lo[a])];
      Cut c;
      c.axis = a;
      c.plane = s;
      shareRanks(low, total - low, ranks, (s - box.lo[a]) * cross, (box.hi[a] - s) * cross, c);
      c.alignment = alignmentOf(g, s);
      c.axisVoxels =
          g.bounds[size_t(a)][size_t(box.hi[a])] - g.bounds[size_t(a)][size_t(box.lo[a])];
      cuts.push_back(c);
    }
  }
  return cuts;
}

Cut bestCut(const CellGrid& g, const CellBox& box, int ranks) {
  const std::vector<Cut> cuts = candidateCuts(g, box, ranks);
  double least = cuts.front().cost;
  for (const Cut& c : cuts) least = std::min(least, c.cost);
  const Cut* best = nullptr;
  for (const Cut& c : cuts)
    if (c.cost <= least * (1 + kAlignmentTolerance) && (!best || better(c, *best))) best = &c;
  return *best;
}

double boxWork(const CellGrid& g, const CellBox& box) {
  double sum = 0;
  for (int z = box.lo[2]; z < box.hi[2]; ++z)
    for (int y = box.lo[1]; y < box.hi[1]; ++y)
      for (int x = box.lo[0]; x < box.hi[0]; ++x) sum += g.work[cellIndex(g.cells, x, y, z)];
  return sum;
}

void checkGrid(const CellGrid& g, int ranks) {
  if (ranks < 1 || ranks > kMaxRanks)
    throw InvalidArgument("rank boxes: " + std::to_string(ranks) + " ranks (1.." +
                          std::to_string(kMaxRanks) + " can share a volume)");
  int64_t cells = 1;
  for (int a = 0; a < 3; ++a) {
    if (g.cells[a] < 1 || g.bounds[size_t(a)].size() != size_t(g.cells[a]) + 1)
      throw InvalidArgument("rank boxes: axis " + std::to_string(a) +
                            " needs at least one block and one more boundary than blocks");
    cells *= g.cells[a];
  }
  if (g.work.size() != size_t(cells))
    throw InvalidArgument("rank boxes: " + std::to_string(g.work.size()) + " work values for " +
                          std::to_string(cells) + " blocks");
  for (double w : g.work)
    if (!(w >= 0) || !std::isfinite(w))
      throw InvalidArgument("rank boxes: a block's work is negative or not finite");
}

}  // namespace

/// The bytes of a finest block's coarser ancestors that fall to it: each ancestor's stored bytes
/// shared among the finest blocks it covers (a view that draws a coarser level there reads them).
double ancestorShare(const AfamFile& file, const Int3& finestIjk) {
  const Partition& p = file.partition();
  double share = 0;
  Int3 ijk = finestIjk;
  for (int level = p.levels() - 2; level >= 0; --level) {
    ijk = p.parent(level + 1, ijk);
    const ModelEntry& e = file.entries()[size_t(file.entryIndex(level, ijk))];
    share += double(e.storedSize) / double(p.cells(level, ijk).cells());
  }
  return share;
}

CellGrid cellWork(const AfamFile& file) {
  const Partition& p = file.partition();
  const int finest = p.levels() - 1;
  CellGrid g;
  g.cells = p.blocksPerAxis(finest);
  g.levels = p.levels();
  for (int a = 0; a < 3; ++a) {
    g.bounds[size_t(a)].assign(size_t(g.cells[a]) + 1, 0);
    for (int i = 0; i < g.cells[a]; ++i) {
      Int3 ijk{0, 0, 0};
      ijk[a] = i;
      g.bounds[size_t(a)][size_t(i) + 1] = p.extent(finest, ijk).hi[a];
    }
  }
  std::vector<double> bytes;  // of the blocks that count; 0 for the others
  double byteSum = 0;
  int64_t counted = 0;
  for (int64_t i = 0; i < p.blockCount(finest); ++i) {
    const Int3 ijk = p.blockFromLinear(finest, i);
    const ModelEntry& e = file.entries()[size_t(file.entryIndex(finest, ijk))];
    const bool counts = countsWork(file, e);
    bytes.push_back(counts ? double(e.storedSize) + ancestorShare(file, ijk) : 0.0);
    byteSum += bytes.back();
    counted += counts ? 1 : 0;
  }
  const double meanBytes = counted && byteSum > 0 ? byteSum / double(counted) : 1.0;
  for (const double b : bytes) g.work.push_back(kWorkFloor + b / meanBytes);
  return g;
}

RankSplit::RankSplit(const CellGrid& grid, int ranks) {
  checkGrid(grid, ranks);
  boxes_.assign(size_t(ranks), CellBox{});
  work_.assign(size_t(ranks), 0.0);
  const CellBox whole{{0, 0, 0}, grid.cells};
  build(grid, whole, 0, int(std::min<int64_t>(ranks, whole.cells())));
}

int RankSplit::build(const CellGrid& grid, const CellBox& box, int firstRank, int ranks) {
  const int id = int(nodes_.size());
  nodes_.emplace_back();
  if (ranks == 1) {
    nodes_[size_t(id)].rank = firstRank;
    boxes_[size_t(firstRank)] = box;
    work_[size_t(firstRank)] = boxWork(grid, box);
    return id;
  }
  const Cut cut = bestCut(grid, box, ranks);
  CellBox low = box, high = box;
  low.hi[cut.axis] = high.lo[cut.axis] = cut.plane;
  const int lowNode = build(grid, low, firstRank, cut.lowRanks);
  const int highNode = build(grid, high, firstRank + cut.lowRanks, ranks - cut.lowRanks);
  Node& n = nodes_[size_t(id)];
  n.axis = cut.axis;
  n.plane = grid.bounds[size_t(cut.axis)][size_t(cut.plane)];
  n.low = lowNode;
  n.high = highNode;
  return id;
}

std::vector<int> RankSplit::visibilityOrder(const RayCamera& camera, const float* boxLo,
                                            const float* boxHi, const Index3& dims) const {
  std::vector<char> lowFirst(nodes_.size(), 1);
  for (size_t i = 0; i < nodes_.size(); ++i) {
    const Node& n = nodes_[i];
    if (n.axis < 0) continue;
    const int a = n.axis;
    const double span = double(boxHi[a]) - double(boxLo[a]);
    const double at = double(boxLo[a]) + span * double(n.plane) / double(dims[size_t(a)] - 1);
    lowFirst[i] = camera.parallel ? camera.forward[a] >= 0.f : double(camera.eye[a]) < at;
  }
  std::vector<int> order;
  visit(0, lowFirst, order);
  for (size_t r = 0; r < boxes_.size(); ++r)
    if (boxes_[r].empty()) order.push_back(int(r));
  return order;
}

void RankSplit::visit(int node, const std::vector<char>& lowFirst, std::vector<int>& order) const {
  const Node& n = nodes_[size_t(node)];
  if (n.axis < 0) {
    order.push_back(n.rank);
    return;
  }
  const bool low = lowFirst[size_t(node)] != 0;
  visit(low ? n.low : n.high, lowFirst, order);
  visit(low ? n.high : n.low, lowFirst, order);
}

CellBox rankBox(const AfamFile& file, int rank, int ranks) {
  if (rank < 0 || rank >= ranks)
    throw InvalidArgument("rank boxes: rank " + std::to_string(rank) + " of " +
                          std::to_string(ranks) + " ranks (ranks are numbered 0 .. " +
                          std::to_string(ranks - 1) + "): the ranks disagree on how many they are");
  return RankSplit::ofFile(file, ranks).boxes()[size_t(rank)];
}

}  // namespace afam
