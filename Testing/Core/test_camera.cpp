// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "afam/base/errors.hpp"
#include "afam/scene/camera.hpp"
#include "scratch_dir.hpp"

using namespace afam;

TEST(Camera, PoseFrameFollowsTheDataReadme) {
  const Pose pose{1.3, 35.0, 120.0};
  const Camera c = Camera::fromPose(pose, 64, 48);
  const double t = 35.0 * M_PI / 180, p = 120.0 * M_PI / 180;
  EXPECT_NEAR(c.eye[0], 1.3 * std::sin(t) * std::cos(p), 1e-12);
  EXPECT_NEAR(c.eye[1], 1.3 * std::sin(t) * std::sin(p), 1e-12);
  EXPECT_NEAR(c.eye[2], 1.3 * std::cos(t), 1e-12);
  // Orthonormal, right-handed (right x up = -forward), looking at the origin.
  EXPECT_NEAR(dot(c.right, c.right), 1, 1e-12);
  EXPECT_NEAR(dot(c.up, c.up), 1, 1e-12);
  EXPECT_NEAR(dot(c.right, c.up), 0, 1e-12);
  EXPECT_NEAR(dot(c.right, c.forward), 0, 1e-12);
  EXPECT_NEAR(dot(c.up, c.forward), 0, 1e-12);
  EXPECT_NEAR(dot(c.forward, c.eye), -1.3, 1e-12);
  const Vec3 x{c.right[1] * c.up[2] - c.right[2] * c.up[1],
               c.right[2] * c.up[0] - c.right[0] * c.up[2],
               c.right[0] * c.up[1] - c.right[1] * c.up[0]};
  EXPECT_NEAR(dot(x, c.forward), -1, 1e-12);
  EXPECT_DOUBLE_EQ(c.tanHalfX, 0.125);
  // The centre pixel looks at the origin; the corner ray is normalize(u, v, -8) in camera space.
  const RayCamera rc = c.toRayCamera();
  float d[3];
  RayCamera r2 = rc;
  r2.width = r2.height = 1;
  rayDirection(r2, 0, 0, d);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(d[a], c.forward[a], 1e-6);
}

TEST(Camera, RejectsDamagedTrajectories) {
  const std::string path = afam_test::scratchPath("bad_trajectory.dat");
  {
    std::ofstream f(path, std::ios::binary);
    f.write("12345678", 8);
  }
  EXPECT_THROW(loadTrajectory(path), FormatError);
  {
    std::ofstream f(path, std::ios::binary);
    const float v[3] = {-1.f, 0.f, 0.f};
    f.write(reinterpret_cast<const char*>(v), sizeof v);
  }
  EXPECT_THROW(loadTrajectory(path), FormatError);
  std::remove(path.c_str());
  EXPECT_THROW(loadTrajectory("/nonexistent/x.dat"), IoError);
}

TEST(Camera, LookAtBuildsAnOrthonormalFrame) {
  const Camera c = Camera::lookAt({3, 0, 0}, {0, 0, 0}, {0, 0, 1}, 30, 100, 50);
  EXPECT_NEAR(c.forward[0], -1, 1e-12);
  EXPECT_NEAR(c.up[2], 1, 1e-12);
  EXPECT_NEAR(c.tanHalfX, 2 * c.tanHalfY, 1e-12);
  EXPECT_THROW(Camera::lookAt({0, 0, 0}, {0, 0, 0}, {0, 0, 1}, 30, 10, 10), InvalidArgument);
}
