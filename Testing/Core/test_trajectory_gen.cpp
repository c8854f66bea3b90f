// SPDX-License-Identifier: BSD-3-Clause
// Generated camera paths: exact orbits and dollies, and an exploration walk whose statistics stay
// in the ranges measured on recorded human paths.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <numeric>

#include "afam/base/errors.hpp"
#include "afam/scene/camera.hpp"
#include "afam/scene/trajectory_gen.hpp"
#include "scratch_dir.hpp"

using namespace afam;

namespace {

// Smallest signed difference b - a of two angles in degrees, in (-180, 180].
double angleStep(double a, double b) {
  double d = std::fmod(b - a, 360.0);
  if (d > 180) d -= 360;
  if (d <= -180) d += 360;
  return d;
}

double mean(const std::vector<double>& v) {
  return std::accumulate(v.begin(), v.end(), 0.0) / double(v.size());
}

double lagOneAutocorrelation(const std::vector<double>& v) {
  const double m = mean(v);
  double num = 0, den = 0;
  for (size_t i = 0; i < v.size(); ++i) {
    den += (v[i] - m) * (v[i] - m);
    if (i > 0) num += (v[i] - m) * (v[i - 1] - m);
  }
  return num / den;
}

}  // namespace

TEST(TrajectoryGen, OrbitIsAnEvenCircle) {
  const auto poses = orbitTrajectory(8, 1.5, 60, 350, 1);
  ASSERT_EQ(poses.size(), 8u);
  for (size_t i = 0; i < poses.size(); ++i) {
    EXPECT_DOUBLE_EQ(poses[i].distance, 1.5);
    EXPECT_DOUBLE_EQ(poses[i].thetaDeg, 60);
    EXPECT_NEAR(poses[i].phiDeg, std::fmod(350 + 45.0 * double(i), 360.0), 1e-12);
    EXPECT_NEAR(std::sqrt(dot(posePosition(poses[i]), posePosition(poses[i]))), 1.5, 1e-12);
  }
  // Consecutive eyes are one chord of 45 degrees apart on a circle of radius 1.5 sin 60.
  const double chord = 2 * 1.5 * std::sin(M_PI / 3) * std::sin(M_PI / 8);
  EXPECT_NEAR(poseDistance(poses[0], poses[1]), chord, 1e-12);
  EXPECT_NEAR(poseDistance(poses[7], poses[0]), chord, 1e-12);
  const auto back = orbitTrajectory(4, 1.2, 90, 0, -0.5);
  EXPECT_NEAR(back[1].phiDeg, 315, 1e-12);
}

TEST(TrajectoryGen, DollyGoesThroughTheVolume) {
  const auto poses = dollyTrajectory(5, 2.0, 0.4, 54.7356, 45);
  ASSERT_EQ(poses.size(), 5u);
  EXPECT_DOUBLE_EQ(poses.front().distance, 2.0);
  EXPECT_DOUBLE_EQ(poses.back().distance, 0.4);
  EXPECT_NEAR(poses[2].distance, 1.2, 1e-12);
  for (size_t i = 1; i < poses.size(); ++i) {
    EXPECT_LT(poses[i].distance, poses[i - 1].distance);
    EXPECT_DOUBLE_EQ(poses[i].thetaDeg, 54.7356);
    EXPECT_DOUBLE_EQ(poses[i].phiDeg, 45);
  }
  // On the diagonal the box [-1, 1]^3 reaches sqrt(3): the first eye is outside, the last inside.
  const Vec3 first = posePosition(poses.front()), last = posePosition(poses.back());
  EXPECT_GT(std::max({std::abs(first[0]), std::abs(first[1]), std::abs(first[2])}), 1.0);
  EXPECT_LT(std::max({std::abs(last[0]), std::abs(last[1]), std::abs(last[2])}), 1.0);
  EXPECT_EQ(dollyTrajectory(1, 2.0, 0.4, 10, 20)[0].distance, 2.0);
}

TEST(TrajectoryGen, WalkIsReproducibleFromItsSeed) {
  const auto a = explorationWalk(400, 7), b = explorationWalk(400, 7), c = explorationWalk(400, 8);
  ASSERT_EQ(a.size(), 400u);
  int differ = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].distance, b[i].distance);
    EXPECT_EQ(a[i].thetaDeg, b[i].thetaDeg);
    EXPECT_EQ(a[i].phiDeg, b[i].phiDeg);
    differ += poseDistance(a[i], c[i]) > 1e-3;
  }
  EXPECT_GT(differ, 390);
}

// Recorded paths (400 views): distance 1.0-2.0 with medians 1.02 and 1.9, mean |d theta| 3.3 and
// 3.7 degrees a view with lag-1 autocorrelation 0.91 and 0.95, median |d phi| 0.8 and 1.0
// degrees, mean eye step 0.10 and 0.15. The walk must stay in the same ranges, for any seed.
TEST(TrajectoryGen, WalkHasTheStatisticsOfAPersonsExploration) {
  for (uint64_t seed : {1, 2, 3, 42, 1000}) {
    SCOPED_TRACE(seed);
    const auto p = explorationWalk(400, seed);
    std::vector<double> dTheta, dPhi, dDistance, step;
    double dMin = 10, dMax = 0;
    for (size_t i = 0; i < p.size(); ++i) {
      EXPECT_GE(p[i].distance, 1.0);
      EXPECT_LE(p[i].distance, 1.7);
      EXPECT_GE(p[i].thetaDeg, 5.0);
      EXPECT_LE(p[i].thetaDeg, 175.0);
      EXPECT_GE(p[i].phiDeg, 0.0);
      EXPECT_LT(p[i].phiDeg, 360.0);
      dMin = std::min(dMin, p[i].distance);
      dMax = std::max(dMax, p[i].distance);
      if (i == 0) continue;
      dTheta.push_back(p[i].thetaDeg - p[i - 1].thetaDeg);
      dPhi.push_back(std::abs(angleStep(p[i - 1].phiDeg, p[i].phiDeg)));
      dDistance.push_back(std::abs(p[i].distance - p[i - 1].distance));
      step.push_back(poseDistance(p[i - 1], p[i]));
    }
    std::vector<double> absTheta;
    for (double d : dTheta) absTheta.push_back(std::abs(d));
    EXPECT_GT(mean(absTheta), 1.5);
    EXPECT_LT(mean(absTheta), 5.0);
    EXPECT_LT(*std::max_element(absTheta.begin(), absTheta.end()), 16.0);
    EXPECT_GT(lagOneAutocorrelation(dTheta), 0.8);
    std::sort(dPhi.begin(), dPhi.end());
    EXPECT_GT(dPhi[dPhi.size() / 2], 0.3);
    EXPECT_LT(dPhi[dPhi.size() / 2], 4.0);
    EXPECT_LT(mean(dDistance), 0.03);
    EXPECT_GT(mean(step), 0.03);
    EXPECT_LT(mean(step), 0.2);
    EXPECT_GT(dMax - dMin, 0.1);  // the user moves in and out, not only around
  }
}

TEST(TrajectoryGen, GeneratedPathsRoundTripThroughTheFileFormat) {
  TrajectoryOptions o;
  o.kind = parseTrajectoryKind("walk");
  o.views = 50;
  o.seed = 5;
  const auto poses = generateTrajectory(o);
  const std::string path = afam_test::scratchPath("traj_gen.dat");
  writeTrajectory(path, poses);
  const auto back = loadTrajectory(path);
  std::remove(path.c_str());
  ASSERT_EQ(back.size(), 50u);
  for (size_t i = 0; i < back.size(); ++i) {
    EXPECT_EQ(float(back[i].distance), float(poses[i].distance));
    EXPECT_EQ(float(back[i].thetaDeg), float(poses[i].thetaDeg));
    EXPECT_EQ(float(back[i].phiDeg), float(poses[i].phiDeg));
  }
}

TEST(TrajectoryGen, RejectsBadOptions) {
  EXPECT_THROW(parseTrajectoryKind("spiral"), InvalidArgument);
  EXPECT_THROW(orbitTrajectory(0, 1.5, 60, 0, 1), InvalidArgument);
  EXPECT_THROW(orbitTrajectory(10, -1, 60, 0, 1), InvalidArgument);
  EXPECT_THROW(orbitTrajectory(10, 1.5, 200, 0, 1), InvalidArgument);
  EXPECT_THROW(dollyTrajectory(10, 2, 0, 60, 0), InvalidArgument);
  EXPECT_THROW(explorationWalk(10, 1, 1.7, 1.0), InvalidArgument);
  EXPECT_THROW(explorationWalk(10, 1, NAN, 1.0), InvalidArgument);
}
