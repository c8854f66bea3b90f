// SPDX-License-Identifier: BSD-3-Clause
#include "afam/scene/view_mapping.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "afam/base/errors.hpp"

namespace afam {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

Vec3 FrameMap::apply(const Vec3& w) const {
  const auto& m = linear;
  return {m[0] * w[0] + m[1] * w[1] + m[2] * w[2] + offset[0],
          m[3] * w[0] + m[4] * w[1] + m[5] * w[2] + offset[1],
          m[6] * w[0] + m[7] * w[1] + m[8] * w[2] + offset[2]};
}

FrameMap frameMapFromWorld(const std::array<double, 16>& worldToData, const Vec3& lo,
                           const Vec3& hi) {
  FrameMap map;
  for (int r = 0; r < 3; ++r) {
    const double center = 0.5 * (lo[r] + hi[r]);
    double half = 0.5 * (hi[r] - lo[r]);
    if (!(half > 0)) half = 1;
    for (int c = 0; c < 3; ++c)
      map.linear[size_t(3 * r + c)] = worldToData[size_t(4 * r + c)] / half;
    map.offset[size_t(r)] = (worldToData[size_t(4 * r + 3)] - center) / half;
  }
  return map;
}

Camera cameraFromFrustum(const ViewFrustum& f, const FrameMap& map, int width, int height) {
  Camera world = f.parallel ? Camera::parallelLookAt(f.position, f.focalPoint, f.viewUp,
                                                     f.parallelScale, width, height)
                            : Camera::lookAt(f.position, f.focalPoint, f.viewUp, f.viewAngleDeg,
                                             width, height);
  // The half extents follow the viewport's aspect ratio (not the image's, which may be rounded),
  // the angle (or scale) vertical unless horizontalViewAngle; the window centre shifts the view
  // in units of the half extents.
  if (f.horizontalViewAngle && !f.parallel) {
    world.tanHalfX = std::tan(0.5 * f.viewAngleDeg * kPi / 180.0);
    world.tanHalfY = world.tanHalfX / f.aspect;
  } else {
    world.tanHalfX = world.tanHalfY * f.aspect;
  }
  world.centerX = f.windowCenter[0] * world.tanHalfX;
  world.centerY = f.windowCenter[1] * world.tanHalfY;
  world.nearDistance = std::max(0.0, f.nearClip);
  Camera c = world.mapped(map.linear, map.offset);
  c.nearDistance = std::max(1e-4, c.nearDistance);
  return c;
}

DepthToRay depthToRay(int tileWidth, int tileHeight, const std::array<double, 16>& m,
                      const FrameMap& map, const Camera& camera) {
  if (tileWidth < 1 || tileHeight < 1 || camera.width < 1 || camera.height < 1 ||
      camera.width > tileWidth || camera.height > tileHeight)
    throw InvalidArgument(
        "depth limits: the image must be at least 1x1 and no larger than the tile");
  DepthToRay t;
  // The frame map is affine: [L o; 0 1] times the projective NDC -> world matrix.
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 3; ++r)
      t.m[4 * r + c] = map.linear[size_t(3 * r)] * m[size_t(c)] +
                       map.linear[size_t(3 * r + 1)] * m[size_t(4 + c)] +
                       map.linear[size_t(3 * r + 2)] * m[size_t(8 + c)] +
                       map.offset[size_t(r)] * m[size_t(12 + c)];
    t.m[12 + c] = m[size_t(12 + c)];
  }
  const Vec3 n = cross(camera.right, camera.up);  // the image plane's normal
  for (int a = 0; a < 3; ++a) {
    t.eye[a] = camera.eye[size_t(a)];
    t.normal[a] = n[size_t(a)];
  }
  t.forwardDotNormal = dot(camera.forward, n) / std::sqrt(dot(camera.forward, camera.forward));
  t.parallel = camera.parallel ? 1 : 0;
  t.tileWidth = tileWidth;
  t.tileHeight = tileHeight;
  t.width = camera.width;
  t.height = camera.height;
  return t;
}

int64_t rayLengthsFromDepth(const float* depth, int tileWidth, int tileHeight,
                            const std::array<double, 16>& m, const FrameMap& map,
                            const Camera& camera, std::vector<float>& limits) {
  const DepthToRay t = depthToRay(tileWidth, tileHeight, m, map, camera);
  const int w = t.width, h = t.height;
  limits.assign(size_t(w) * size_t(h), std::numeric_limits<float>::infinity());
  int64_t limited = 0;
  for (int y = 0; y < h; ++y) {                           // y = 0: bottom row
    float* row = &limits[size_t(h - 1 - y) * size_t(w)];  // row 0 = top
    for (int x = 0; x < w; ++x) {
      row[x] = rayLimitFromDepth(t, depth, x, y);
      limited += std::isinf(row[x]) ? 0 : 1;
    }
  }
  return limited;
}

}  // namespace afam
