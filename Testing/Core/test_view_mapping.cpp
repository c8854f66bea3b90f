// SPDX-License-Identifier: BSD-3-Clause
// view_mapping.hpp: a placed volume's world -> frame map, a viewport's camera from its frustum
// (aspect, horizontal view angle, window centre, near plane) and the ray lengths that a depth
// buffer written with an OpenGL-style projection gives back: a point drawn at distance D along a
// pixel's ray must stop that ray at D (in the normalised frame).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "afam/base/errors.hpp"
#include "afam/render/raycast.hpp"
#include "afam/scene/view_mapping.hpp"

using namespace afam;

namespace {

using M4 = std::array<double, 16>;

M4 mul(const M4& a, const M4& b) {
  M4 c{};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k)
        c[size_t(4 * i + j)] += a[size_t(4 * i + k)] * b[size_t(4 * k + j)];
  return c;
}

/// Gauss-Jordan with partial pivoting.
M4 inverse(M4 a) {
  M4 inv{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  for (int c = 0; c < 4; ++c) {
    int p = c;
    for (int r = c + 1; r < 4; ++r)
      if (std::abs(a[size_t(4 * r + c)]) > std::abs(a[size_t(4 * p + c)])) p = r;
    for (int k = 0; k < 4; ++k) {
      std::swap(a[size_t(4 * c + k)], a[size_t(4 * p + k)]);
      std::swap(inv[size_t(4 * c + k)], inv[size_t(4 * p + k)]);
    }
    const double d = a[size_t(5 * c)];
    for (int k = 0; k < 4; ++k) {
      a[size_t(4 * c + k)] /= d;
      inv[size_t(4 * c + k)] /= d;
    }
    for (int r = 0; r < 4; ++r) {
      if (r == c) continue;
      const double f = a[size_t(4 * r + c)];
      for (int k = 0; k < 4; ++k) {
        a[size_t(4 * r + k)] -= f * a[size_t(4 * c + k)];
        inv[size_t(4 * r + k)] -= f * inv[size_t(4 * c + k)];
      }
    }
  }
  return inv;
}

/// World -> clip of a look-at camera (OpenGL conventions, centred frustum).
M4 composite(const Camera& c, double nearClip, double farClip) {
  const Vec3 &r = c.right, &u = c.up, &f = c.forward, &e = c.eye;
  const M4 view{r[0],  r[1],  r[2],  -dot(r, e), u[0], u[1], u[2], -dot(u, e),
                -f[0], -f[1], -f[2], dot(f, e),  0,    0,    0,    1};
  const double n = nearClip, fa = farClip;
  M4 proj{};
  proj[0] = 1 / c.tanHalfX;
  proj[5] = 1 / c.tanHalfY;
  if (c.parallel) {
    proj[10] = -2 / (fa - n);
    proj[11] = -(fa + n) / (fa - n);
    proj[15] = 1;
  } else {
    proj[10] = -(fa + n) / (fa - n);
    proj[11] = -2 * fa * n / (fa - n);
    proj[14] = -1;
  }
  return mul(proj, view);
}

/// Window depth of a world point.
float windowDepth(const M4& m, const Vec3& p) {
  double clip[4];
  for (int r = 0; r < 4; ++r)
    clip[r] = m[size_t(4 * r)] * p[0] + m[size_t(4 * r + 1)] * p[1] + m[size_t(4 * r + 2)] * p[2] +
              m[size_t(4 * r + 3)];
  return float(0.5 * (clip[2] / clip[3] + 1.0));
}

ViewFrustum frustum(bool parallel) {
  ViewFrustum f;
  f.position = {2.5, -1.0, 1.5};
  f.focalPoint = {0.1, 0.2, -0.1};
  f.viewUp = {0, 0, 1};
  f.parallel = parallel;
  f.viewAngleDeg = 35;
  f.parallelScale = 1.3;
  f.aspect = 40.0 / 30.0;
  f.nearClip = 0.5;
  return f;
}

}  // namespace

TEST(ViewMapping, FrameMapTakesTheDataBoxOntoTheUnitCube) {
  M4 toData{1, 0, 0, -3, 0, 2, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};  // x - 3, 2 y, z
  const FrameMap map = frameMapFromWorld(toData, {0, 0, -5}, {10, 20, 5});
  const Vec3 a = map.apply({3, 0, -5}), b = map.apply({13, 10, 5});
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(a[size_t(k)], -1.0, 1e-12);
    EXPECT_NEAR(b[size_t(k)], 1.0, 1e-12);
  }
  // A flat axis keeps half-width 1 about its centre instead of dividing by zero.
  const FrameMap flat =
      frameMapFromWorld({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}, {0, 0, 4}, {2, 2, 4});
  EXPECT_NEAR(flat.apply({1, 1, 6})[2], 2.0, 1e-12);
}

TEST(ViewMapping, CameraFollowsAspectHorizontalAngleWindowCentreAndNearPlane) {
  ViewFrustum f = frustum(false);
  const FrameMap identity;
  const Camera c = cameraFromFrustum(f, identity, 20, 15);
  const double t = std::tan(0.5 * 35 * M_PI / 180);
  EXPECT_NEAR(c.tanHalfY, t, 1e-12);
  EXPECT_NEAR(c.tanHalfX, t * 40.0 / 30.0, 1e-12);  // the viewport's aspect, not 20 / 15 rounded
  EXPECT_NEAR(c.nearDistance, 0.5, 1e-12);
  EXPECT_EQ(c.width, 20);
  EXPECT_EQ(c.height, 15);
  f.horizontalViewAngle = true;
  f.windowCenter = {0.5, -0.25};
  f.nearClip = 0;
  const Camera h = cameraFromFrustum(f, identity, 20, 15);
  EXPECT_NEAR(h.tanHalfX, t, 1e-12);
  EXPECT_NEAR(h.tanHalfY, t * 30.0 / 40.0, 1e-12);
  EXPECT_NEAR(h.centerX, 0.5 * t, 1e-12);
  EXPECT_NEAR(h.centerY, -0.25 * t * 30.0 / 40.0, 1e-12);
  EXPECT_NEAR(h.nearDistance, 1e-4, 1e-15);  // rays never start at the eye itself
  // Parallel: the scale is half the height; the horizontal-angle flag does not apply.
  f = frustum(true);
  f.horizontalViewAngle = true;
  const Camera p = cameraFromFrustum(f, identity, 20, 15);
  EXPECT_TRUE(p.parallel);
  EXPECT_NEAR(p.tanHalfY, 1.3, 1e-12);
  EXPECT_NEAR(p.tanHalfX, 1.3 * 40.0 / 30.0, 1e-12);
  f.position = f.focalPoint;
  EXPECT_THROW(cameraFromFrustum(f, identity, 20, 15), InvalidArgument);
}

TEST(ViewMapping, DepthOfAPointOnAPixelRayStopsThatRayThere) {
  for (bool parallel : {false, true}) {
    const ViewFrustum f = frustum(parallel);
    const int w = 40, h = 30;
    const FrameMap identity;
    Camera world = cameraFromFrustum(f, identity, w, h);  // the world camera (identity map)
    const M4 m = composite(world, 0.5, 20.0);
    FrameMap map;  // a stretching placement: the frame distance is not the world distance
    map.linear = {0.5, 0, 0, 0, 0.25, 0, 0, 0, 1};
    map.offset = {0.1, -0.2, 0.3};
    const Camera framed = cameraFromFrustum(f, map, w, h);
    std::vector<float> depth(size_t(w) * h, 1.0f);
    const RayCamera rc = world.toRayCamera();
    const int px = 27, py = 8;  // py: row from the top, as the ray caster counts
    float o[3], d[3];
    pixelRay(rc, px, py, o, d);
    const double D = 3.2;
    const Vec3 p{o[0] + D * d[0], o[1] + D * d[1], o[2] + D * d[2]};
    depth[size_t(h - 1 - py) * w + px] = windowDepth(m, p);
    std::vector<float> limits;
    const int64_t n = rayLengthsFromDepth(depth.data(), w, h, inverse(m), map, framed, limits);
    ASSERT_EQ(n, 1);
    ASSERT_EQ(limits.size(), size_t(w) * h);
    // Perspective: the frame distance from the mapped eye; parallel: along the mapped ray from
    // the eye plane. Both are the frame length of the world segment from o to p.
    const Vec3 a = map.apply({o[0], o[1], o[2]}), b = map.apply(p);
    const double expected =
        std::sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) +
                  (b[2] - a[2]) * (b[2] - a[2]));
    EXPECT_NEAR(limits[size_t(py) * w + px], expected, 2e-4 * expected) << "parallel " << parallel;
    EXPECT_TRUE(std::isinf(limits[0]));
  }
}

TEST(ViewMapping, ASmallerImageTakesTheNearestDepthItCovers) {
  const ViewFrustum f = frustum(false);
  const FrameMap identity;
  const Camera world = cameraFromFrustum(f, identity, 40, 30);
  const Camera half = cameraFromFrustum(f, identity, 20, 15);
  const M4 m = composite(world, 0.5, 20.0);
  std::vector<float> depth(size_t(40) * 30, 1.0f);
  depth[size_t(1) * 40 + 1] = 0.9f;   // tile pixel (1, 1), bottom-left
  depth[size_t(0) * 40 + 0] = 0.95f;  // farther, in the same 2 x 2 cell
  std::vector<float> limits;
  ASSERT_EQ(rayLengthsFromDepth(depth.data(), 40, 30, inverse(m), identity, half, limits), 1);
  const float got = limits[size_t(14) * 20 + 0];  // image row 14 (of 15) from the top = bottom
  EXPECT_TRUE(std::isfinite(got));
  // The nearer of the two depths, at the image pixel's own centre.
  std::vector<float> only(size_t(40) * 30, 1.0f);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 2; ++x) only[size_t(y) * 40 + x] = 0.9f;
  std::vector<float> expected;
  rayLengthsFromDepth(only.data(), 40, 30, inverse(m), identity, half, expected);
  EXPECT_EQ(got, expected[size_t(14) * 20]);
  EXPECT_EQ(rayLengthsFromDepth(depth.data(), 40, 30, inverse(m), identity, world, limits), 2);
  const Camera larger = cameraFromFrustum(f, identity, 41, 30);
  EXPECT_THROW(rayLengthsFromDepth(depth.data(), 40, 30, inverse(m), identity, larger, limits),
               InvalidArgument);
}
