// SPDX-License-Identifier: BSD-3-Clause
// From a viewer's frustum and depth buffer, as a scene graph such as VTK describes them, to the
// normalised frame the renderer works in: the world -> frame map of a placed volume, the camera
// of a viewport (tiles, off-centre windows, horizontal view angles, parallel projection), and the
// per-pixel ray lengths that stop rays at opaque geometry already drawn. Plain numbers only, so
// any front end uses the same math and it is tested without a window.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "afam/scene/camera.hpp"
#include "afam/scene/depth_limits.hpp"

namespace afam {

/// A viewer's frustum in the world, in the terms of VTK's vtkCamera.
struct ViewFrustum {
  Vec3 position{0, 0, 1}, focalPoint{0, 0, 0}, viewUp{0, 1, 0};
  bool parallel = false;
  double viewAngleDeg = 30;  ///< perspective: full angle, vertical unless horizontalViewAngle
  bool horizontalViewAngle = false;          ///< viewAngleDeg spans the width instead of the height
  double parallelScale = 1;                  ///< parallel: half the view's height
  double aspect = 1;                         ///< width / height of the viewport (the tile)
  std::array<double, 2> windowCenter{0, 0};  ///< shift of the view, in units of its half extents
  double nearClip = 0;                       ///< world distance of the near clipping plane
};

/// World -> normalised frame: x' = linear x + offset (row-major 3x3).
struct FrameMap {
  std::array<double, 9> linear{1, 0, 0, 0, 1, 0, 0, 0, 1};
  Vec3 offset{0, 0, 0};
  Vec3 apply(const Vec3& world) const;
};

/// The map that takes the world through worldToData (row-major 4x4, affine: the inverse of the
/// placed volume's matrix) into the data, then the data box [lo, hi] onto [-1, 1]^3, each axis
/// on its own (a flat axis, lo == hi, is taken as half-width 1).
FrameMap frameMapFromWorld(const std::array<double, 16>& worldToData, const Vec3& lo,
                           const Vec3& hi);

/// The camera of `frustum` for a width x height image, mapped into the normalised frame through
/// `map` (Camera::mapped). Rays start at the near clipping plane, and never closer to the eye than
/// 1e-4 in the frame. Throws InvalidArgument as Camera::lookAt, parallelLookAt and mapped do.
Camera cameraFromFrustum(const ViewFrustum& frustum, const FrameMap& map, int width, int height);

/// The per-frame constants of rayLengthsFromDepth (for the GPU's copy of the same math, see
/// depth_limits.hpp). Throws InvalidArgument as rayLengthsFromDepth does.
DepthToRay depthToRay(int tileWidth, int tileHeight, const std::array<double, 16>& ndcToWorld,
                      const FrameMap& map, const Camera& camera);

/// Ray lengths that stop each pixel's ray at the opaque geometry of a depth buffer.
/// depth: window depths in [0, 1] of a tileWidth x tileHeight tile, row 0 at the bottom (OpenGL's
/// order), 1 = nothing drawn. ndcToWorld: the inverse of the viewer's composite projection
/// (row-major 4x4, normalised device z in [-1, 1]), which linearises a perspective depth exactly.
/// camera: the mapped camera the rays come from; its width x height image may be smaller than the
/// tile (each of its pixels takes the nearest depth among the tile pixels it covers).
/// limits gets width * height floats, row 0 at the top: perspective, the frame distance from the
/// eye; parallel, the distance along the ray from the eye plane; +infinity where nothing opaque
/// was drawn. Returns the number of limited pixels.
int64_t rayLengthsFromDepth(const float* depth, int tileWidth, int tileHeight,
                            const std::array<double, 16>& ndcToWorld, const FrameMap& map,
                            const Camera& camera, std::vector<float>& limits);

}  // namespace afam
