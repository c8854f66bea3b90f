// SPDX-License-Identifier: BSD-3-Clause
#include "afam/ranks/box_frame.hpp"

#include <string>

#include "afam/base/errors.hpp"

namespace afam {

namespace {

/// The normalised-frame coordinate of voxel coordinate x on axis a (toVoxel's inverse).
float normalisedOf(const FrameView& v, int a, float x) {
  return v.voxelPerUnit[a] > 0.f ? v.boxLo[a] + x / v.voxelPerUnit[a] : v.boxLo[a];
}

void cullOutside(PreparedFrame& frame, const CellBox& box) {
  const int* n = frame.view.gridDims;
  size_t i = 0;
  for (int z = 0; z < n[2]; ++z)
    for (int y = 0; y < n[1]; ++y)
      for (int x = 0; x < n[0]; ++x, ++i)
        if (!box.contains({x, y, z})) frame.cellSlot[i] = -1;
}

}  // namespace

void clipFrameToBox(PreparedFrame& frame, const CellBox& box) {
  FrameView& v = frame.view;
  for (int a = 0; a < 3; ++a)
    if (!box.empty() && (box.lo[a] < 0 || box.hi[a] > v.gridDims[a]))
      throw InvalidArgument("box frame: the box's cells " + std::to_string(box.lo[a]) + ".." +
                            std::to_string(box.hi[a]) + " on axis " + std::to_string(a) +
                            " lie outside the frame's " + std::to_string(v.gridDims[a]));
  cullOutside(frame, box);
  v.clipped = 1;
  for (int a = 0; a < 3; ++a) {
    const std::vector<float>& bounds = frame.cellBounds[size_t(a)];
    const int lo = box.empty() ? 0 : box.lo[a], hi = box.empty() ? 0 : box.hi[a];
    v.clipLo[a] = normalisedOf(v, a, bounds[size_t(lo)]);
    v.clipHi[a] = box.empty() ? v.clipLo[a] : normalisedOf(v, a, bounds[size_t(hi)]);
    if (v.voxelPerUnit[a] <= 0.f) v.clipHi[a] = v.boxHi[a];  // a one-sample axis: all of it
  }
  frame.bind();
}

}  // namespace afam
