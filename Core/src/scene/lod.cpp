// SPDX-License-Identifier: BSD-3-Clause
#include "afam/scene/lod.hpp"

#include <algorithm>
#include <cmath>

#include "afam/scene/transfer_function.hpp"

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

namespace {
Vec3 combine(const Vec3& a, double s, const Vec3& b) {
  return {a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]};
}
/// n, flipped if needed so that n.inside > 0.
Vec3 toward(Vec3 n, const Vec3& inside) {
  if (dot(n, inside) < 0)
    for (double& x : n) x = -x;
  return n;
}
/// Whether block b's box lies outside the frustum (and so does every block inside it).
bool outsideBox(const FrustumPlanes& frustum, const Partition& p, const BlockRef& b) {
  double lo[3], hi[3];
  blockBox(p, b.level, b.ijk, lo, hi);
  return frustum.outside(lo, hi);
}

}  // namespace

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
  if (d <= 0 && !c.parallel) return level + 1;  // eye inside: refine
  double voxel = 0;
  for (int a = 0; a < 3; ++a)
    if (p.dims()[a] > 1) voxel = std::max(voxel, 2.0 / double(p.dims()[a] - 1));
  const double spacing = voxel * double(p.stride(level));
  // Half the view's height at the block: parallel, tanHalfY |up|; perspective, at distance d
  // along a ray, d tanHalfY |up| / |forward| (both |.| = 1 unless the camera was mapped()).
  const double upLength = std::sqrt(dot(c.up, c.up));
  const double halfHeight = c.parallel
                                ? c.tanHalfY * upLength
                                : d * c.tanHalfY * upLength / std::sqrt(dot(c.forward, c.forward));
  const double pixels = spacing / halfHeight * (0.5 * c.height);
  return pixels > options_.pixelBudget ? level + 1 : level;
}

std::vector<BlockRef> LodSelector::cut(const Partition& p, const Camera& camera) const {
  return cut(p, camera, nullptr);
}

std::vector<BlockRef> LodSelector::cut(const Partition& p, const Camera& camera,
                                       const FrustumPlanes* prune) const {
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
    if (b.level < finest && !(prune && outsideBox(*prune, p, b)) &&
        desiredLevel(p, b.level, b.ijk, camera) > b.level) {
      for (const Int3& c : p.children(b.level, b.ijk)) stack.push_back({b.level + 1, c, -1});
    } else {
      out.push_back(b);
    }
  }
  return out;
}

FrustumPlanes::FrustumPlanes(const Camera& c) {
  // Five planes with inward normals n through points q: n.(x - q) >= 0 inside. Each side plane is
  // spanned by an edge direction of the frustum and a frame vector, so the normals come from cross
  // products and hold for a mapped (non-orthonormal) frame too. For an orthonormal perspective
  // frame they are forward * tanHalf +- right / up; near: forward.
  const Vec3 f = c.forward, r = c.right, u = c.up, e = c.eye;
  if (!c.parallel) {
    // left: edge f + (cx - tx) r, spans u; right: f + (cx + tx) r; bottom/top likewise with u.
    n[0] = toward(cross(u, combine(f, c.centerX - c.tanHalfX, r)), combine(f, c.centerX, r));
    n[1] = toward(cross(u, combine(f, c.centerX + c.tanHalfX, r)), combine(f, c.centerX, r));
    n[2] = toward(cross(r, combine(f, c.centerY - c.tanHalfY, u)), combine(f, c.centerY, u));
    n[3] = toward(cross(r, combine(f, c.centerY + c.tanHalfY, u)), combine(f, c.centerY, u));
    for (int k = 0; k < 4; ++k) q[k] = e;
  } else {
    const Vec3 nx = cross(u, f), ny = cross(r, f);  // normals of the side planes' pairs
    n[0] = toward(nx, r);
    q[0] = combine(e, c.centerX - c.tanHalfX, r);
    n[1] = {-n[0][0], -n[0][1], -n[0][2]};
    q[1] = combine(e, c.centerX + c.tanHalfX, r);
    n[2] = toward(ny, u);
    q[2] = combine(e, c.centerY - c.tanHalfY, u);
    n[3] = {-n[2][0], -n[2][1], -n[2][2]};
    q[3] = combine(e, c.centerY + c.tanHalfY, u);
  }
  // Near plane: parallel to the image plane (spanned by right and up), nearDistance along the
  // unit view direction from the eye.
  Vec3 nn = toward(cross(r, u), f);
  const double nnLength = std::sqrt(dot(nn, nn));
  for (double& x : nn) x /= nnLength;
  const double fLength = std::sqrt(dot(f, f));
  n[4] = nn;
  q[4] = combine(e, c.nearDistance / fLength, f);
}

bool FrustumPlanes::outside(const double lo[3], const double hi[3]) const {
  for (int k = 0; k < 5; ++k) {
    // The box corner farthest along the normal (p-vertex); if even it is outside, the box is.
    double s = 0;
    for (int a = 0; a < 3; ++a) {
      const double v = n[k][a] >= 0 ? hi[a] : lo[a];
      s += n[k][a] * (v - q[k][a]);
    }
    if (s < -1e-9) return true;
  }
  return false;
}

bool LodSelector::outsideFrustum(const Camera& c, const double lo[3], const double hi[3]) {
  return FrustumPlanes(c).outside(lo, hi);
}

Selection LodSelector::select(const AfamFile& file, const Camera& camera,
                              const std::vector<float>& tfTable, double tfLo, double tfHi,
                              bool drawMissing) const {
  Selection sel;
  const Partition& p = file.partition();
  const auto& entries = file.entries();
  const VolumeHeader& h = file.header();
  const double margin0 = 0.01 * std::max(0.0, h.valueMax - h.valueMin);
  const FrustumPlanes frustum(camera);
  for (BlockRef b : cut(p, camera, options_.frustumCulling ? &frustum : nullptr)) {
    b.entry = file.entryIndex(b.level, b.ijk);
    const ModelEntry& e = entries[size_t(b.entry)];
    const int64_t bytes = int64_t(e.size);
    sel.counts.cutBlocks++;
    sel.counts.cutBytes += bytes;
    if (options_.frustumCulling) {
      if (outsideBox(frustum, p, b)) {
        sel.counts.frustumBlocks++;
        sel.counts.frustumBytes += bytes;
        continue;
      }
    }
    if (e.kind == BlockKind::Empty && !drawMissing) {
      sel.counts.emptyBlocks++;
      continue;
    }
    if (options_.tfCulling && !tfTable.empty() && e.kind != BlockKind::Empty &&
        !(e.masked && drawMissing)) {
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
