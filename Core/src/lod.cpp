// SPDX-License-Identifier: BSD-3-Clause
#include "afam/lod.hpp"

#include <algorithm>
#include <cmath>

#include "afam/transfer_function.hpp"

namespace afam {

void blockBox(const Partition& p, int level, Int3 ijk, double lo[3], double hi[3]) {
  const BlockExtent e = p.extent(level, ijk);
  for (int a = 0; a < 3; ++a) {
    const double n1 = double(p.dims()[a] - 1);
    if (n1 <= 0) {
      lo[a] = -1;
      hi[a] = 1;
      continue;
    }
    lo[a] = -1.0 + 2.0 * double(e.lo[a]) / n1;
    hi[a] = -1.0 + 2.0 * double(e.hi[a]) / n1;
  }
}

int LodSelector::desiredLevel(const Partition& p, int level, Int3 ijk, const Camera& c) const {
  const int finest = p.levels() - 1;
  if (options_.forceLevel >= 0) return std::min(options_.forceLevel, finest);
  double lo[3], hi[3];
  blockBox(p, level, ijk, lo, hi);
  if (options_.policy == LodPolicy::Distance) {
    double d2 = 0;
    for (int a = 0; a < 3; ++a) {
      const double m = 0.5 * (lo[a] + hi[a]) - c.eye[a];
      d2 += m * m;
    }
    const int band = int(std::floor(std::sqrt(d2) / options_.bandWidth));
    return std::max(0, finest - std::max(0, band));
  }
  // Screen policy: projected sample spacing at the block's nearest point.
  double d2 = 0;
  for (int a = 0; a < 3; ++a) {
    const double q = std::clamp(c.eye[a], lo[a], hi[a]) - c.eye[a];
    d2 += q * q;
  }
  const double d = std::sqrt(d2);
  if (d <= 0) return level + 1;  // eye inside: refine
  double voxel = 0;
  for (int a = 0; a < 3; ++a)
    if (p.dims()[a] > 1) voxel = std::max(voxel, 2.0 / double(p.dims()[a] - 1));
  const double spacing = voxel * double(p.stride(level));
  const double pixels = spacing / (d * c.tanHalfY) * (0.5 * c.height);
  return pixels > options_.pixelBudget ? level + 1 : level;
}

std::vector<BlockRef> LodSelector::cut(const Partition& p, const Camera& camera) const {
  std::vector<BlockRef> out;
  std::vector<BlockRef> stack;
  const Int3 b0 = p.blocksPerAxis(0);
  for (int z = b0[2] - 1; z >= 0; --z)
    for (int y = b0[1] - 1; y >= 0; --y)
      for (int x = b0[0] - 1; x >= 0; --x) stack.push_back({0, {x, y, z}, -1});
  const int finest = p.levels() - 1;
  while (!stack.empty()) {
    const BlockRef b = stack.back();
    stack.pop_back();
    if (b.level < finest && desiredLevel(p, b.level, b.ijk, camera) > b.level) {
      for (const Int3& c : p.children(b.level, b.ijk)) stack.push_back({b.level + 1, c, -1});
    } else {
      out.push_back(b);
    }
  }
  return out;
}

bool LodSelector::outsideFrustum(const Camera& c, const double lo[3], const double hi[3]) {
  // Planes through the eye with inward normals: n.(x - eye) >= 0 inside.
  //   left/right: forward * tanHalfX +- right; bottom/top: forward * tanHalfY +- up; near: forward.
  double planes[5][3];
  for (int a = 0; a < 3; ++a) {
    planes[0][a] = c.forward[a] * c.tanHalfX + c.right[a];
    planes[1][a] = c.forward[a] * c.tanHalfX - c.right[a];
    planes[2][a] = c.forward[a] * c.tanHalfY + c.up[a];
    planes[3][a] = c.forward[a] * c.tanHalfY - c.up[a];
    planes[4][a] = c.forward[a];
  }
  for (int k = 0; k < 5; ++k) {
    // The box corner farthest along the normal (p-vertex); if even it is outside, the box is.
    double s = 0;
    for (int a = 0; a < 3; ++a) {
      const double v = planes[k][a] >= 0 ? hi[a] : lo[a];
      s += planes[k][a] * (v - c.eye[a]);
    }
    const double eps = 1e-9;
    if (k == 4 ? s < c.nearDistance - eps : s < -eps) return true;
  }
  return false;
}

Selection LodSelector::select(const AfamFile& file, const Camera& camera,
                              const std::vector<float>& tfTable, double tfLo, double tfHi) const {
  Selection sel;
  const Partition& p = file.partition();
  const auto& entries = file.entries();
  const VolumeHeader& h = file.header();
  const double margin0 = 0.01 * std::max(0.0, h.valueMax - h.valueMin);
  for (BlockRef b : cut(p, camera)) {
    b.entry = file.entryIndex(b.level, b.ijk);
    const ModelEntry& e = entries[size_t(b.entry)];
    const int64_t bytes = int64_t(e.size);
    sel.counts.cutBlocks++;
    sel.counts.cutBytes += bytes;
    if (options_.frustumCulling) {
      double lo[3], hi[3];
      blockBox(p, b.level, b.ijk, lo, hi);
      if (outsideFrustum(camera, lo, hi)) {
        sel.counts.frustumBlocks++;
        sel.counts.frustumBytes += bytes;
        continue;
      }
    }
    if (options_.tfCulling && !tfTable.empty()) {
      const double margin = std::max(double(e.maxError), margin0);
      if (TransferFunction::maxOpacity(tfTable, tfLo, tfHi, double(e.minValue) - margin,
                                       double(e.maxValue) + margin) <= 0.f) {
        sel.counts.tfBlocks++;
        sel.counts.tfBytes += bytes;
        continue;
      }
    }
    sel.counts.visibleBlocks++;
    sel.counts.visibleBytes += bytes;
    sel.visible.push_back(b);
  }
  return sel;
}

}  // namespace afam
