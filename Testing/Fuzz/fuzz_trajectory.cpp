// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: the trajectory loader (loadTrajectory), then a camera for every loaded pose.
// Input: the file's bytes.
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "afam/base/errors.hpp"
#include "afam/scene/camera.hpp"
#include "memory_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static afam_fuzz::MemoryFile memory;
  const std::string& path = memory.write(data, size);
  try {
    for (const afam::Pose& pose : afam::loadTrajectory(path)) {
      if (!(pose.distance > 0) || !std::isfinite(pose.thetaDeg) || !std::isfinite(pose.phiDeg))
        __builtin_trap();  // the loader promised finite poses with a positive distance
      const afam::Camera camera = afam::Camera::fromPose(pose, 8, 6);
      (void)camera.toRayCamera();
    }
  } catch (const afam::Error&) {
  }
  return 0;
}
