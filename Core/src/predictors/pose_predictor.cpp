// SPDX-License-Identifier: BSD-3-Clause
#include "afam/predictors/pose_predictor.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>

#include "afam/errors.hpp"
#include "afam/predictors/appa.hpp"
#include "afam/predictors/forecache.hpp"
#include "afam/predictors/lstm.hpp"

namespace afam {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
}  // namespace

Vec3 posePosition(const Pose& p) {
  const double t = p.thetaDeg * kDeg, f = p.phiDeg * kDeg;
  return {p.distance * std::sin(t) * std::cos(f), p.distance * std::sin(t) * std::sin(f),
          p.distance * std::cos(t)};
}

Pose poseFromPosition(const Vec3& e) {
  Pose p;
  p.distance = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
  if (p.distance <= 0) return Pose{0, 0, 0};
  p.thetaDeg = std::acos(std::fmax(-1.0, std::fmin(1.0, e[2] / p.distance))) / kDeg;
  double phi = std::atan2(e[1], e[0]) / kDeg;
  if (phi < 0) phi += 360.0;
  if (phi >= 360.0) phi -= 360.0;
  p.phiDeg = phi;
  return p;
}

double poseDistance(const Pose& a, const Pose& b) {
  const Vec3 pa = posePosition(a), pb = posePosition(b);
  const double dx = pa[0] - pb[0], dy = pa[1] - pb[1], dz = pa[2] - pb[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

void writeTrajectory(const std::string& path, const std::vector<Pose>& poses) {
  const std::size_t n = poses.size();
  std::vector<float> buf(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    buf[i] = static_cast<float>(poses[i].distance);
    buf[n + i] = static_cast<float>(poses[i].thetaDeg);
    buf[2 * n + i] = static_cast<float>(poses[i].phiDeg);
  }
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw IoError("cannot open '" + tmp + "' for writing");
    out.write(reinterpret_cast<const char*>(buf.data()),
              static_cast<std::streamsize>(buf.size() * sizeof(float)));
    out.flush();
    if (!out) {
      std::remove(tmp.c_str());
      throw IoError("writing '" + tmp + "' failed (disk full?)");
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw IoError("cannot rename '" + tmp + "' to '" + path + "'");
  }
}

Pose StayPosePredictor::predictNext() const {
  return history().empty() ? Pose{} : history().back();
}

Pose LinearPosePredictor::predictNext() const {
  const auto& h = history();
  if (h.empty()) return Pose{};
  if (h.size() < 2) return h.back();
  const Vec3 a = posePosition(h[h.size() - 2]), b = posePosition(h.back());
  return poseFromPosition({2 * b[0] - a[0], 2 * b[1] - a[1], 2 * b[2] - a[2]});
}

std::unique_ptr<PosePredictor> makePosePredictor(const std::string& name,
                                                 const PosePredictorOptions& options) {
  if (name == "none") return std::make_unique<StayPosePredictor>();
  if (name == "linear") return std::make_unique<LinearPosePredictor>();
  if (name == "appa") return std::make_unique<AppaPosePredictor>();
  if (name == "forecache") return std::make_unique<ForeCachePosePredictor>();
  if (name == "lstm")
    return std::make_unique<LstmPosePredictor>(
        options.lstmWeights.empty() ? defaultLstmWeightsPath() : options.lstmWeights);
  throw InvalidArgument("unknown predictor '" + name +
                        "' (expected none, linear, appa, forecache or lstm)");
}

}  // namespace afam
