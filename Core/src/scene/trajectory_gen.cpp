// SPDX-License-Identifier: BSD-3-Clause
#include "afam/scene/trajectory_gen.hpp"

#include <algorithm>
#include <cmath>

#include "afam/base/errors.hpp"

namespace afam {
namespace {

constexpr double kPi = 3.14159265358979323846;

void checkViews(int views) {
  if (views < 1)
    throw InvalidArgument("trajectory: views must be at least 1, not " + std::to_string(views));
}

void checkDistance(const char* what, double d) {
  if (!(d > 0) || !std::isfinite(d))
    throw InvalidArgument(std::string("trajectory: ") + what + " must be positive and finite");
}

void checkTheta(double thetaDeg) {
  if (!(thetaDeg >= 0 && thetaDeg <= 180))
    throw InvalidArgument("trajectory: theta must be in [0, 180] degrees");
}

double wrapDegrees(double a) {
  a = std::fmod(a, 360.0);
  return a < 0 ? a + 360.0 : a;
}

/// SplitMix64 over a counter: the same numbers from the same seed on every platform and standard
/// library (std::normal_distribution's algorithm is left to the implementation).
class PortableRandom {
 public:
  explicit PortableRandom(uint64_t seed) : state_(seed) {}
  double uniform() { return double(next() >> 11) * (1.0 / 9007199254740992.0); }  // [0, 1)
  double normal(double sigma) {                                                   // Box-Muller
    const double u1 = 1.0 - uniform(), u2 = uniform();
    return sigma * std::sqrt(-2.0 * std::log(u1)) * std::cos(2 * kPi * u2);
  }

 private:
  uint64_t next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  uint64_t state_;
};

// The walk's constants, fitted to the two recorded paths (see the header): per view, theta's
// velocity is an AR(1) process with coefficient 0.93 and noise 1.4 degrees (stationary mean
// |step| about 3 degrees), phi's with 0.9 and 0.9 degrees (about 1.6 degrees), the distance's with
// 0.85 and 0.006 (about 0.009, as recorded). Theta reflects inside [5, 175]: the recorded users
// stayed off the poles.
constexpr double kThetaKeep = 0.93, kThetaNoise = 1.4;
constexpr double kPhiKeep = 0.9, kPhiNoise = 0.9;
constexpr double kDistanceKeep = 0.85, kDistanceNoise = 0.006;
constexpr double kThetaLow = 5, kThetaHigh = 175;
constexpr double kPauseChance = 0.01, kPauseSlowdown = 0.2;

struct WalkState {
  double theta, phi, distance;
  double vTheta, vPhi, vDistance;
  int pauseLeft = 0;
};

void stepWalk(WalkState& s, PortableRandom& rng, double minDistance, double maxDistance) {
  if (s.pauseLeft == 0 && rng.uniform() < kPauseChance) s.pauseLeft = 5 + int(rng.uniform() * 16);
  const double slow = s.pauseLeft > 0 ? kPauseSlowdown : 1.0;
  if (s.pauseLeft > 0) --s.pauseLeft;
  s.vTheta = kThetaKeep * s.vTheta + rng.normal(kThetaNoise);
  s.vPhi = kPhiKeep * s.vPhi + rng.normal(kPhiNoise);
  s.vDistance = kDistanceKeep * s.vDistance + rng.normal(kDistanceNoise);
  s.theta += slow * s.vTheta;
  if (s.theta < kThetaLow || s.theta > kThetaHigh) {
    s.theta = s.theta < kThetaLow ? 2 * kThetaLow - s.theta : 2 * kThetaHigh - s.theta;
    s.vTheta = -s.vTheta;
  }
  s.phi = wrapDegrees(s.phi + slow * s.vPhi);
  s.distance += slow * s.vDistance;
  if (s.distance < minDistance || s.distance > maxDistance) {
    s.distance = std::clamp(s.distance, minDistance, maxDistance);
    s.vDistance = 0;  // the user rests against the limit
  }
}

}  // namespace

TrajectoryKind parseTrajectoryKind(const std::string& name) {
  if (name == "orbit") return TrajectoryKind::Orbit;
  if (name == "dolly") return TrajectoryKind::Dolly;
  if (name == "walk") return TrajectoryKind::Walk;
  throw InvalidArgument("unknown trajectory kind '" + name + "' (expected orbit, dolly or walk)");
}

const char* trajectoryKindName(TrajectoryKind kind) {
  switch (kind) {
    case TrajectoryKind::Orbit:
      return "orbit";
    case TrajectoryKind::Dolly:
      return "dolly";
    case TrajectoryKind::Walk:
      return "walk";
  }
  return "unknown";
}

std::vector<Pose> orbitTrajectory(int views, double distance, double thetaDeg, double phiStartDeg,
                                  double turns) {
  checkViews(views);
  checkDistance("distance", distance);
  checkTheta(thetaDeg);
  if (!std::isfinite(phiStartDeg) || !std::isfinite(turns))
    throw InvalidArgument("trajectory: phi and turns must be finite");
  std::vector<Pose> poses(static_cast<size_t>(views));
  for (int i = 0; i < views; ++i)
    poses[size_t(i)] =
        Pose{distance, thetaDeg, wrapDegrees(phiStartDeg + 360.0 * turns * i / views)};
  return poses;
}

std::vector<Pose> dollyTrajectory(int views, double fromDistance, double toDistance,
                                  double thetaDeg, double phiDeg) {
  checkViews(views);
  checkDistance("the first distance", fromDistance);
  checkDistance("the last distance", toDistance);
  checkTheta(thetaDeg);
  if (!std::isfinite(phiDeg)) throw InvalidArgument("trajectory: phi must be finite");
  std::vector<Pose> poses(static_cast<size_t>(views));
  for (int i = 0; i < views; ++i) {
    const double t = views == 1 ? 0.0 : double(i) / double(views - 1);
    poses[size_t(i)] =
        Pose{fromDistance + (toDistance - fromDistance) * t, thetaDeg, wrapDegrees(phiDeg)};
  }
  return poses;
}

std::vector<Pose> explorationWalk(int views, uint64_t seed, double minDistance,
                                  double maxDistance) {
  checkViews(views);
  checkDistance("the smallest distance", minDistance);
  checkDistance("the largest distance", maxDistance);
  if (minDistance > maxDistance)
    throw InvalidArgument("trajectory: the smallest distance exceeds the largest");
  PortableRandom rng(seed);
  WalkState s{};
  s.theta = 20 + 140 * rng.uniform();
  s.phi = 360 * rng.uniform();
  s.distance = minDistance + 0.3 * (maxDistance - minDistance) * rng.uniform();
  s.vTheta = rng.normal(3.0);
  s.vPhi = rng.normal(1.5);
  std::vector<Pose> poses;
  poses.reserve(size_t(views));
  for (int i = 0; i < views; ++i) {
    poses.push_back(Pose{s.distance, s.theta, s.phi});
    stepWalk(s, rng, minDistance, maxDistance);
  }
  return poses;
}

std::vector<Pose> generateTrajectory(const TrajectoryOptions& o) {
  switch (o.kind) {
    case TrajectoryKind::Orbit:
      return orbitTrajectory(o.views, o.distance, o.thetaDeg, o.phiDeg, o.turns);
    case TrajectoryKind::Dolly:
      return dollyTrajectory(o.views, o.fromDistance, o.toDistance, o.thetaDeg, o.phiDeg);
    case TrajectoryKind::Walk:
      return explorationWalk(o.views, o.seed, o.minDistance, o.maxDistance);
  }
  throw InvalidArgument("trajectory: unknown kind");
}

}  // namespace afam
