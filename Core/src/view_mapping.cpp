// SPDX-License-Identifier: BSD-3-Clause
#include "afam/view_mapping.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "afam/errors.hpp"

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

namespace {

/// The nearest depth among the tile pixels that image pixel (x, y) covers (y = 0: bottom row).
float nearestDepth(const float* depth, int tileWidth, int tileHeight, int width, int height, int x,
                   int y) {
  const int y0 = y * tileHeight / height, y1 = std::max(y0 + 1, (y + 1) * tileHeight / height);
  const int x0 = x * tileWidth / width, x1 = std::max(x0 + 1, (x + 1) * tileWidth / width);
  float z = 1.0f;
  for (int yt = y0; yt < y1; ++yt)
    for (int xt = x0; xt < x1; ++xt)
      z = std::min(z, depth[size_t(yt) * size_t(tileWidth) + size_t(xt)]);
  return z;
}

}  // namespace

int64_t rayLengthsFromDepth(const float* depth, int tileWidth, int tileHeight,
                            const std::array<double, 16>& m, const FrameMap& map,
                            const Camera& camera, std::vector<float>& limits) {
  if (tileWidth < 1 || tileHeight < 1 || camera.width < 1 || camera.height < 1 ||
      camera.width > tileWidth || camera.height > tileHeight)
    throw InvalidArgument(
        "depth limits: the image must be at least 1x1 and no larger than the tile");
  const int w = camera.width, h = camera.height;
  const Vec3 n = cross(camera.right, camera.up);  // the image plane's normal
  const double dn = dot(camera.forward, n) / std::sqrt(dot(camera.forward, camera.forward));
  limits.assign(size_t(w) * size_t(h), std::numeric_limits<float>::infinity());
  int64_t limited = 0;
  for (int y = 0; y < h; ++y) {  // y = 0: bottom row
    const double ny = 2.0 * (y + 0.5) / h - 1.0;
    float* row = &limits[size_t(h - 1 - y) * size_t(w)];  // row 0 = top
    for (int x = 0; x < w; ++x) {
      const float z = nearestDepth(depth, tileWidth, tileHeight, w, h, x, y);
      if (!(z < 1.0f)) continue;  // the far plane: nothing opaque here
      const double ndc[4] = {2.0 * (x + 0.5) / w - 1.0, ny, 2.0 * z - 1.0, 1.0};
      double p[4];
      for (int r = 0; r < 4; ++r)
        p[r] = m[size_t(4 * r)] * ndc[0] + m[size_t(4 * r + 1)] * ndc[1] +
               m[size_t(4 * r + 2)] * ndc[2] + m[size_t(4 * r + 3)];
      if (!(std::abs(p[3]) > 0)) continue;
      const Vec3 q = map.apply({p[0] / p[3], p[1] / p[3], p[2] / p[3]});
      const Vec3 d{q[0] - camera.eye[0], q[1] - camera.eye[1], q[2] - camera.eye[2]};
      // Perspective: the distance from the eye. Parallel: (p - eye).n / (forward.n) with n the
      // image plane's normal (every ray starts on the eye plane).
      row[x] = float(camera.parallel ? dot(d, n) / dn : std::sqrt(dot(d, d)));
      ++limited;
    }
  }
  return limited;
}

}  // namespace afam
