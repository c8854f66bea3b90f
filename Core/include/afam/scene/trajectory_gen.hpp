// SPDX-License-Identifier: BSD-3-Clause
// Generated camera paths in the trajectory format of camera.hpp (Pose: distance, theta, phi in
// degrees; the volume spans [-1, 1]^3 and the camera looks at the origin). They stand in for
// recorded human explorations wherever a path is needed: the demo, the tests, the benchmarks and
// the training of the next-pose predictor. Written with writeTrajectory (camera.hpp).
//
// Three kinds:
//   - orbit: a circle at a fixed distance and polar angle, phi advancing evenly;
//   - dolly: a straight line from a distance outside the volume towards the origin, through the
//     volume's box (the camera ends inside it);
//   - walk: a seeded random exploration with the statistics measured on two recorded human paths
//     of 400 views each: distances mostly in [1.0, 1.7], often resting on 1.0, changing about 0.01
//     a view; theta moving 3-4 degrees a view with a lag-1 autocorrelation above 0.9 (smooth
//     turns); phi drifting about 1-2 degrees a view; now and then the user pauses.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "afam/scene/camera.hpp"

namespace afam {

enum class TrajectoryKind { Orbit, Dolly, Walk };

struct TrajectoryOptions {
  TrajectoryKind kind = TrajectoryKind::Walk;
  int views = 400;            ///< number of points of view (>= 1)
  uint64_t seed = 1;          ///< walk: the same seed gives the same path
  double distance = 1.5;      ///< orbit: distance of the eye from the origin
  double thetaDeg = 60;       ///< orbit and dolly: polar angle (degrees, in [0, 180])
  double phiDeg = 30;         ///< dolly: azimuth; orbit: azimuth of the first view
  double turns = 1;           ///< orbit: full turns over the path (negative: clockwise)
  double fromDistance = 2.0;  ///< dolly: first distance
  double toDistance = 0.25;   ///< dolly: last distance (> 0)
  double minDistance = 1.0;   ///< walk: distances stay in [minDistance, maxDistance]
  double maxDistance = 1.7;
};

/// Parses orbit|dolly|walk. Throws InvalidArgument naming the accepted kinds.
TrajectoryKind parseTrajectoryKind(const std::string& name);
const char* trajectoryKindName(TrajectoryKind kind);

/// The path the options describe. Throws InvalidArgument for views < 1, non-positive or
/// non-finite distances, theta outside [0, 180], or minDistance > maxDistance.
std::vector<Pose> generateTrajectory(const TrajectoryOptions& options);

std::vector<Pose> orbitTrajectory(int views, double distance, double thetaDeg, double phiStartDeg,
                                  double turns);
std::vector<Pose> dollyTrajectory(int views, double fromDistance, double toDistance,
                                  double thetaDeg, double phiDeg);
std::vector<Pose> explorationWalk(int views, uint64_t seed, double minDistance = 1.0,
                                  double maxDistance = 1.7);

}  // namespace afam
