// SPDX-License-Identifier: BSD-3-Clause
// The camera as a ray caster sees it: a trivially copyable RayCamera and the ray of each pixel,
// written once for the host and the device (render/raycast.hpp casts along these rays; Camera in
// camera.hpp converts to it).
//
// ---------------------------------------------------------------------------------------------
// Camera and pixels
// ---------------------------------------------------------------------------------------------
//  Pixel (px, py), py = 0 the TOP row, has the camera-space direction
//      d = normalize((su * tanHalfX + centerX) * right + (sv * tanHalfY + centerY) * up + forward),
//      su = 2 (px + 0.5) / width - 1,  sv = 1 - 2 (py + 0.5) / height  (centre 0 but for VTK's
//      WindowCenter / screenshot tiles). Parallel projection: d = forward, the ray starts at
//      eye + (su tanHalfX + centerX) right + (sv tanHalfY + centerY) up.
//  The authors' camera (data README) is tanHalfX = tanHalfY = 1/8: direction normalize(u, v, -8).
#pragma once

#include <stdint.h>

#include "afam/base/host_device.hpp"

#if !defined(__CUDACC__)
#include <cmath>
#endif

namespace afam {

/// Camera of one frame in the normalised frame. Trivially copyable.
/// right/up/forward are unit and orthonormal for the trajectory cameras; a camera mapped from
/// the world into the normalised frame (Camera::mapped: a non-cubic volume, a transformed
/// vtkVolume) keeps the images of the world's unit vectors, which need not be either.
struct RayCamera {
  float eye[3] = {0.f, 0.f, 5.f};
  float right[3] = {1.f, 0.f, 0.f};
  float up[3] = {0.f, 1.f, 0.f};
  float forward[3] = {0.f, 0.f, -1.f};  ///< viewing direction
  /// Perspective: tan of half the horizontal / vertical view angle (authors: 1/8). Parallel:
  /// half the view's width / height in units of |right| / |up|.
  float tanHalfX = 0.125f;
  float tanHalfY = 0.125f;
  /// Off-centre frustum (VTK's WindowCenter, tiles of a magnified screenshot): the image spans
  /// su in [centerX - tanHalfX, centerX + tanHalfX], sv likewise. 0: centred.
  float centerX = 0.f, centerY = 0.f;
  float nearDistance = 1e-3f;  ///< rays start no closer than this to the eye (parallel: eye plane)
  int width = 1, height = 1;
  int32_t parallel = 0;  ///< 1: orthographic, every ray along forward from its own origin
  /// 1: a ray's step is sampleDistance / |stepMetric d| (row-major 3x3), so that every step
  /// covers the same length in the world however the frame stretches it; 0: steps of
  /// sampleDistance (the normalised frame is the world up to a similarity).
  int32_t hasStepMetric = 0;
  float stepMetric[9] = {1.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f};
};

// ---------------------------------------------------------------------------------------------
// Ray setup
// ---------------------------------------------------------------------------------------------

/// Image-plane coordinates of pixel (px, py)'s centre in units of right and up (see the header).
AFAM_HD void pixelOffsets(const RayCamera& c, int px, int py, float& su, float& sv) {
  su = (2.f * (float(px) + 0.5f) / float(c.width) - 1.f) * c.tanHalfX + c.centerX;
  sv = (1.f - 2.f * (float(py) + 0.5f) / float(c.height)) * c.tanHalfY + c.centerY;
}

/// Unit ray direction of pixel (px, py), py = 0 the top row (see the header comment).
AFAM_HD void rayDirection(const RayCamera& c, int px, int py, float* d) {
  float su, sv;
  pixelOffsets(c, px, py, su, sv);
  float x = su * c.right[0] + sv * c.up[0] + c.forward[0];
  float y = su * c.right[1] + sv * c.up[1] + c.forward[1];
  float z = su * c.right[2] + sv * c.up[2] + c.forward[2];
  const float inv = 1.f / sqrtf(x * x + y * y + z * z);
  d[0] = x * inv;
  d[1] = y * inv;
  d[2] = z * inv;
}

/// Ray of pixel (px, py), py = 0 the top row: origin o and unit direction d. Perspective: o is
/// the eye, d as rayDirection. Parallel: d = forward / |forward|, o on the eye plane.
AFAM_HD void pixelRay(const RayCamera& c, int px, int py, float* o, float* d) {
  if (!c.parallel) {
    o[0] = c.eye[0];
    o[1] = c.eye[1];
    o[2] = c.eye[2];
    rayDirection(c, px, py, d);
    return;
  }
  float su, sv;
  pixelOffsets(c, px, py, su, sv);
  for (int a = 0; a < 3; ++a) o[a] = c.eye[a] + su * c.right[a] + sv * c.up[a];
  const float inv = 1.f / sqrtf(c.forward[0] * c.forward[0] + c.forward[1] * c.forward[1] +
                                c.forward[2] * c.forward[2]);
  d[0] = c.forward[0] * inv;
  d[1] = c.forward[1] * inv;
  d[2] = c.forward[2] * inv;
}

/// Step along unit direction d that covers sampleDistance of world length (RayCamera::stepMetric).
AFAM_HD float rayStep(const RayCamera& c, const float* d, float sampleDistance) {
  if (!c.hasStepMetric) return sampleDistance;
  const float* m = c.stepMetric;
  const float x = m[0] * d[0] + m[1] * d[1] + m[2] * d[2];
  const float y = m[3] * d[0] + m[4] * d[1] + m[5] * d[2];
  const float z = m[6] * d[0] + m[7] * d[1] + m[8] * d[2];
  return sampleDistance / sqrtf(x * x + y * y + z * z);
}

}  // namespace afam
