// SPDX-License-Identifier: BSD-3-Clause
#include "afam/scene/camera.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>

#include "afam/base/atomic_write.hpp"
#include "afam/base/errors.hpp"

namespace afam {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

/// The unit vector from the origin towards the eye of a pose (t, p: theta and phi in radians).
Vec3 poseDirection(double t, double p) {
  return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}

Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
bool normalize(Vec3& a) {
  const double n = std::sqrt(dot(a, a));
  if (!(n > 1e-300)) return false;
  for (double& x : a) x /= n;
  return true;
}

}  // namespace

Vec3 posePosition(const Pose& pose) {
  const Vec3 dir = poseDirection(pose.thetaDeg * kPi / 180.0, pose.phiDeg * kPi / 180.0);
  return {pose.distance * dir[0], pose.distance * dir[1], pose.distance * dir[2]};
}

Pose poseFromPosition(const Vec3& e) {
  Pose p;
  p.distance = std::sqrt(dot(e, e));
  if (p.distance <= 0) return Pose{0, 0, 0};
  p.thetaDeg = std::acos(std::fmax(-1.0, std::fmin(1.0, e[2] / p.distance))) / kDeg;
  double phi = std::atan2(e[1], e[0]) / kDeg;
  if (phi < 0) phi += 360.0;
  if (phi >= 360.0) phi -= 360.0;
  p.phiDeg = phi;
  return p;
}

double poseDistance(const Pose& a, const Pose& b) {
  const Vec3 d = sub(posePosition(a), posePosition(b));
  return std::sqrt(dot(d, d));
}

Camera Camera::fromPose(const Pose& pose, int width, int height) {
  if (width < 1 || height < 1) throw InvalidArgument("camera: image size must be at least 1x1");
  const double t = pose.thetaDeg * kPi / 180.0, p = pose.phiDeg * kPi / 180.0;
  Camera c;
  const Vec3 dir = poseDirection(t, p);
  c.eye = posePosition(pose);
  c.right = {std::cos(t) * std::cos(p), std::cos(t) * std::sin(p), -std::sin(t)};
  c.up = {-std::sin(p), std::cos(p), 0.0};
  c.forward = {-dir[0], -dir[1], -dir[2]};
  c.tanHalfX = c.tanHalfY = 0.125;
  c.width = width;
  c.height = height;
  return c;
}

Camera Camera::lookAt(const Vec3& eye, const Vec3& focal, const Vec3& viewUp, double viewAngleDeg,
                      int width, int height) {
  if (width < 1 || height < 1) throw InvalidArgument("camera: image size must be at least 1x1");
  if (!(viewAngleDeg > 0 && viewAngleDeg < 179))
    throw InvalidArgument("camera: view angle must be in (0, 179) degrees");
  Camera c;
  c.eye = eye;
  c.forward = sub(focal, eye);
  if (!normalize(c.forward)) throw InvalidArgument("camera: eye and focal point coincide");
  c.right = cross(c.forward, viewUp);
  if (!normalize(c.right))
    throw InvalidArgument("camera: view up is parallel to the view direction");
  c.up = cross(c.right, c.forward);
  c.tanHalfY = std::tan(0.5 * viewAngleDeg * kPi / 180.0);
  c.tanHalfX = c.tanHalfY * double(width) / double(height);
  c.width = width;
  c.height = height;
  return c;
}

Camera Camera::parallelLookAt(const Vec3& eye, const Vec3& focal, const Vec3& viewUp,
                              double parallelScale, int width, int height) {
  if (!(parallelScale > 0) || !std::isfinite(parallelScale))
    throw InvalidArgument("camera: parallel scale must be positive and finite");
  Camera c = lookAt(eye, focal, viewUp, 30.0, width, height);
  c.parallel = true;
  c.tanHalfY = parallelScale;
  c.tanHalfX = parallelScale * double(width) / double(height);
  return c;
}

Camera Camera::mapped(const std::array<double, 9>& m, const Vec3& offset) const {
  const double det = m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
                     m[2] * (m[3] * m[7] - m[4] * m[6]);
  bool finite = std::isfinite(det);
  for (double x : offset) finite = finite && std::isfinite(x);
  if (!finite || !(std::abs(det) > 1e-300))
    throw InvalidArgument("camera: the map into the normalised frame is singular or not finite");
  auto apply = [&](const Vec3& v) {
    return Vec3{m[0] * v[0] + m[1] * v[1] + m[2] * v[2], m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
                m[6] * v[0] + m[7] * v[1] + m[8] * v[2]};
  };
  Camera c = *this;
  c.eye = apply(eye);
  for (int a = 0; a < 3; ++a) c.eye[a] += offset[a];
  c.right = apply(right);
  c.up = apply(up);
  c.forward = apply(forward);
  const double forwardLength = std::sqrt(dot(forward, forward));
  c.nearDistance = nearDistance * std::sqrt(dot(c.forward, c.forward)) / forwardLength;
  // Inverse (normalised -> world) by cofactors, scaled to unit volume scale.
  std::array<double, 9> inv{(m[4] * m[8] - m[5] * m[7]) / det, (m[2] * m[7] - m[1] * m[8]) / det,
                            (m[1] * m[5] - m[2] * m[4]) / det, (m[5] * m[6] - m[3] * m[8]) / det,
                            (m[0] * m[8] - m[2] * m[6]) / det, (m[2] * m[3] - m[0] * m[5]) / det,
                            (m[3] * m[7] - m[4] * m[6]) / det, (m[1] * m[6] - m[0] * m[7]) / det,
                            (m[0] * m[4] - m[1] * m[3]) / det};
  c.lengthUnit = std::cbrt(1.0 / std::abs(det));
  for (double& x : inv) x /= c.lengthUnit;
  // A similarity (scaled rotation) leaves lengths alone: inv^T inv = I.
  double offIdentity = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const double g = inv[i] * inv[j] + inv[3 + i] * inv[3 + j] + inv[6 + i] * inv[6 + j];
      offIdentity = std::max(offIdentity, std::abs(g - (i == j ? 1.0 : 0.0)));
    }
  c.hasStepMetric = offIdentity > 1e-9;
  c.stepMetric = c.hasStepMetric ? inv : std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1};
  return c;
}

void Camera::orthonormalize() {
  if (!normalize(forward)) forward = {0, 0, -1};
  right = cross(forward, up);
  if (!normalize(right)) {
    right = cross(forward, Vec3{0, 0, 1});
    if (!normalize(right)) right = cross(forward, Vec3{0, 1, 0}), normalize(right);
  }
  up = cross(right, forward);
  normalize(up);
}

RayCamera Camera::toRayCamera() const {
  RayCamera r;
  for (int a = 0; a < 3; ++a) {
    r.eye[a] = float(eye[a]);
    r.right[a] = float(right[a]);
    r.up[a] = float(up[a]);
    r.forward[a] = float(forward[a]);
  }
  r.tanHalfX = float(tanHalfX);
  r.tanHalfY = float(tanHalfY);
  r.centerX = float(centerX);
  r.centerY = float(centerY);
  r.nearDistance = float(nearDistance);
  r.width = width;
  r.height = height;
  r.parallel = parallel ? 1 : 0;
  r.hasStepMetric = hasStepMetric ? 1 : 0;
  for (int i = 0; i < 9; ++i) r.stepMetric[i] = float(stepMetric[size_t(i)]);
  return r;
}

std::vector<Pose> loadTrajectory(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("trajectory " + path + ": cannot open");
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw IoError("trajectory " + path + ": read failed");
  if (bytes.empty()) throw FormatError("trajectory " + path + ": empty file");
  if (bytes.size() % 12 != 0)
    throw FormatError("trajectory " + path + ": " + std::to_string(bytes.size()) +
                      " bytes is not 3 float32 per point of view (a multiple of 12)");
  const size_t n = bytes.size() / 12;
  std::vector<float> f(3 * n);
  std::memcpy(f.data(), bytes.data(), bytes.size());  // little-endian host assumed (x86/ARM)
  std::vector<Pose> poses(n);
  for (size_t i = 0; i < n; ++i) {
    const float d = f[i], t = f[n + i], p = f[2 * n + i];
    if (!std::isfinite(d) || !std::isfinite(t) || !std::isfinite(p))
      throw FormatError("trajectory " + path + ": point of view " + std::to_string(i) +
                        " has a non-finite value");
    if (!(d > 0))
      throw FormatError("trajectory " + path + ": point of view " + std::to_string(i) +
                        " has distance " + std::to_string(d) + " (must be > 0)");
    poses[i] = Pose{d, t, p};
  }
  return poses;
}

void writeTrajectory(const std::string& path, const std::vector<Pose>& poses) {
  const std::size_t n = poses.size();
  std::vector<float> buf(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    buf[i] = static_cast<float>(poses[i].distance);
    buf[n + i] = static_cast<float>(poses[i].thetaDeg);
    buf[2 * n + i] = static_cast<float>(poses[i].phiDeg);
  }
  writeFileAtomically(path, buf.data(), buf.size() * sizeof(float), "trajectory");
}

}  // namespace afam
