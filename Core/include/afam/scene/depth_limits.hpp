// SPDX-License-Identifier: BSD-3-Clause
// Per-pixel ray length limits from a depth buffer (opaque geometry stops the rays): the math shared
// by the CPU (rayLengthsFromDepth in view_mapping.hpp) and the GPU (the depth kernel of
// CudaKernels, which reads an OpenGL depth copy in device memory). Plain data and inline math only.
#pragma once

#include <cmath>
#include <limits>

#include "afam/base/host_device.hpp"

namespace afam {

/// How a window depth becomes a ray length, for one frame (built by depthToRay, view_mapping.hpp).
struct DepthToRay {
  double m[16];      ///< normalised device coordinates -> normalised frame (row-major, projective)
  double eye[3];     ///< the camera's eye in the frame
  double normal[3];  ///< the image plane's normal (parallel projection)
  double forwardDotNormal = 1;  ///< dot(forward, normal) / |forward|
  int parallel = 0;
  int tileWidth = 0, tileHeight = 0;  ///< the depth buffer's size (row 0 at the bottom)
  int width = 0, height = 0;          ///< the cast image's size (at most the tile's)
};

/// The nearest depth among the tile pixels that image pixel (x, y) covers (y = 0: bottom row).
AFAM_HD float nearestTileDepth(const DepthToRay& t, const float* depth, int x, int y) {
  const int y0 = y * t.tileHeight / t.height;
  const int y1 =
      (y + 1) * t.tileHeight / t.height > y0 + 1 ? (y + 1) * t.tileHeight / t.height : y0 + 1;
  const int x0 = x * t.tileWidth / t.width;
  const int x1 =
      (x + 1) * t.tileWidth / t.width > x0 + 1 ? (x + 1) * t.tileWidth / t.width : x0 + 1;
  float z = 1.0f;
  for (int yt = y0; yt < y1; ++yt)
    for (int xt = x0; xt < x1; ++xt) {
      const float d = depth[static_cast<long long>(yt) * t.tileWidth + xt];
      z = d < z ? d : z;
    }
  return z;
}

/// The ray length limit of image pixel (x, y) (y = 0: bottom row): perspective, the frame
/// distance from the eye to the surface; parallel, the distance along the ray from the eye
/// plane; +infinity where nothing opaque was drawn (depth 1, the far plane).
AFAM_HD float rayLimitFromDepth(const DepthToRay& t, const float* depth, int x, int y) {
  const float inf = std::numeric_limits<float>::infinity();
  const float z = nearestTileDepth(t, depth, x, y);
  if (!(z < 1.0f)) return inf;
  const double ndc[4] = {2.0 * (x + 0.5) / t.width - 1.0, 2.0 * (y + 0.5) / t.height - 1.0,
                         2.0 * z - 1.0, 1.0};
  double p[4];
  for (int r = 0; r < 4; ++r)
    p[r] = t.m[4 * r] * ndc[0] + t.m[4 * r + 1] * ndc[1] + t.m[4 * r + 2] * ndc[2] + t.m[4 * r + 3];
  if (!(p[3] > 0 || p[3] < 0)) return inf;
  const double d[3] = {p[0] / p[3] - t.eye[0], p[1] / p[3] - t.eye[1], p[2] / p[3] - t.eye[2]};
  if (t.parallel)
    return float((d[0] * t.normal[0] + d[1] * t.normal[1] + d[2] * t.normal[2]) /
                 t.forwardDotNormal);
  return float(sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
}

}  // namespace afam
