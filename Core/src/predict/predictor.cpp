// SPDX-License-Identifier: BSD-3-Clause
#include "afam/predict/predictor.hpp"

namespace afam {

bool LinearPredictor::predict(const std::vector<Camera>& h, Camera& next) const {
  if (h.size() < 2) return false;
  const Camera& a = h[h.size() - 2];
  const Camera& b = h.back();
  next = b;
  for (int i = 0; i < 3; ++i) {
    next.eye[i] = 2 * b.eye[i] - a.eye[i];
    next.forward[i] = 2 * b.forward[i] - a.forward[i];
    next.up[i] = 2 * b.up[i] - a.up[i];
    next.right[i] = 2 * b.right[i] - a.right[i];
  }
  // An orthonormal frame stays one; a mapped frame (Camera::mapped: lengths and angles carry the
  // world-to-normalised map, and a parallel view's size) keeps its extrapolated vectors.
  if (!next.hasStepMetric && !next.parallel && b.lengthUnit == 1) next.orthonormalize();
  return true;
}

Pose predictNextPose(const Predictor& predictor, std::vector<Camera>& history, const Pose& pose,
                     int width, int height) {
  history.push_back(Camera::fromPose(pose, width, height));
  if (history.size() > kPredictorHistory) history.erase(history.begin());
  Camera next;
  return predictor.predict(history, next) ? poseFromPosition(next.eye) : pose;
}

}  // namespace afam
