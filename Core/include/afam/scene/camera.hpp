// SPDX-License-Identifier: BSD-3-Clause
// Cameras in the normalised frame (the volume spans [-1, 1]^3) and trajectory files: recorded
// human explorations (the paper's) or generated paths (trajectory_gen.hpp), in one convention.
//
// Trajectory file: 3 N little-endian float32: N distances, N theta (degrees), N phi (degrees).
// A pose puts the eye at distance * (sin t cos p, sin t sin p, cos t), looking at the origin, with
// the frame R = Rz(phi) Ry(theta):
//   right   = (cos t cos p, cos t sin p, -sin t)
//   up      = (-sin p, cos p, 0)
//   forward = -(sin t cos p, sin t sin p, cos t)
// and the authors' pinhole: a pixel's camera-space direction is normalize(u, v, -8), u, v in
// [-1, 1] (tanHalfX = tanHalfY = 1/8, a full view angle of about 14.25 degrees).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "afam/scene/ray_camera.hpp"

namespace afam {

using Vec3 = std::array<double, 3>;

inline double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

/// One recorded point of view (the trajectory file's three numbers).
struct Pose {
  double distance = 1.5, thetaDeg = 0, phiDeg = 0;
};

/// Eye position of a pose in the normalised frame (the eye of Camera::fromPose).
Vec3 posePosition(const Pose& pose);
/// The pose whose eye is at `eye` (phi in [0, 360), theta in [0, 180]); eye = 0 gives distance 0.
Pose poseFromPosition(const Vec3& eye);
/// Euclidean distance between the eye positions of two poses.
double poseDistance(const Pose& a, const Pose& b);

/// Pinhole (or orthographic) camera with an explicit frame in the normalised frame: orthonormal
/// for the trajectory and look-at cameras; after mapped(), the images of the world's unit vectors.
struct Camera {
  Vec3 eye{0, 0, 5};
  Vec3 right{1, 0, 0};
  Vec3 up{0, 1, 0};
  Vec3 forward{0, 0, -1};
  /// Perspective: tan of half the view angles. Parallel: half the view's width / height in units
  /// of |right| / |up|.
  double tanHalfX = 0.125, tanHalfY = 0.125;
  /// Off-centre frustum: the image spans [center - tanHalf, center + tanHalf] in the same units
  /// (VTK's WindowCenter times tanHalf; the tiles of a magnified screenshot). 0: centred.
  double centerX = 0, centerY = 0;
  double nearDistance = 0.01;  ///< rays start no closer to the eye (near plane inside the volume)
  int width = 256, height = 256;
  bool parallel = false;  ///< orthographic projection (rays along forward)
  /// Set by mapped() when the map is not a similarity: a ray's step is sampleDistance divided by
  /// |stepMetric d| (row-major), the world length of unit normalised direction d in units of
  /// lengthUnit, so that steps are equally long in the world in every direction.
  bool hasStepMetric = false;
  std::array<double, 9> stepMetric{1, 0, 0, 0, 1, 0, 0, 0, 1};
  /// World length of one normalised-frame unit (the cube root of the map's volume scale) after
  /// mapped(); 1 otherwise. Sample and opacity distances given in the world divide by it.
  double lengthUnit = 1;

  /// The authors' camera for a recorded pose (tanHalf = 1/8 on both axes, any image size).
  static Camera fromPose(const Pose& pose, int width, int height);
  /// General look-at camera; viewAngleDeg is the full vertical angle, the horizontal one follows
  /// the aspect ratio. Throws InvalidArgument when eye == focal or up is parallel to the view.
  static Camera lookAt(const Vec3& eye, const Vec3& focal, const Vec3& viewUp, double viewAngleDeg,
                       int width, int height);
  /// Orthographic look-at camera; parallelScale is half the view's height (VTK's
  /// ParallelScale), the width follows the aspect ratio. Throws as lookAt, and for
  /// parallelScale <= 0.
  static Camera parallelLookAt(const Vec3& eye, const Vec3& focal, const Vec3& viewUp,
                               double parallelScale, int width, int height);
  /// This camera (given in the world) seen in the frame x' = linear x + offset (row-major 3x3,
  /// invertible): every pixel's ray maps onto the same points. The eye is mapped, the frame
  /// vectors are multiplied by `linear` (no longer unit or orthogonal unless it is a similarity),
  /// nearDistance becomes the mapped length along the view direction; stepMetric, hasStepMetric
  /// and lengthUnit describe the map (see above). Throws InvalidArgument for a singular or
  /// non-finite map.
  Camera mapped(const std::array<double, 9>& linear, const Vec3& offset) const;
  /// The trivially copyable form castRay uses.
  RayCamera toRayCamera() const;
  /// Re-orthonormalises right/up against forward (after extrapolation, for example).
  void orthonormalize();
};

/// Reads a trajectory file. Throws IoError (cannot open/read) or FormatError (size not a multiple
/// of 12 bytes, empty, non-finite value, distance <= 0), naming the file and the offending index.
std::vector<Pose> loadTrajectory(const std::string& path);

/// Writes poses in the trajectory format (3 N float32: distances, theta, phi) to a temporary file
/// renamed into place. Throws IoError.
void writeTrajectory(const std::string& path, const std::vector<Pose>& poses);

}  // namespace afam
