// SPDX-License-Identifier: BSD-3-Clause
// The one interface of the predictors of the next point of view, and the two that need no data
// (none and linear); predictor_factory.hpp builds every kind by name.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "afam/scene/camera.hpp"

namespace afam {

/// Cameras of the latest points of view a predictor is given (the renderer's history, and
/// `afam predict`'s): the LSTM needs its window plus one.
constexpr std::size_t kPredictorHistory = 16;

/// Predicts the camera of the next point of view from the history of cameras (oldest first): the
/// one predictor interface. makePrefetchPredictor (predictors/prefetch_predictors.hpp) builds
/// every kind by name. Stateful predictors learn from the cameras of a history they have not seen
/// yet and start over when a history does not continue the previous one.
class Predictor {
 public:
  virtual ~Predictor() = default;
  virtual const char* name() const = 0;
  /// False when no prediction is made (too little history, or the `none` predictor).
  virtual bool predict(const std::vector<Camera>& history, Camera& next) const = 0;
  /// Predictors that know the blocks (file entries) the next view needs without a visibility
  /// computation (APPA's table, ForeCache's signature ranking) fill `entries`, most important
  /// first, and return true; the others return false and the caller selects the view of
  /// predict()'s camera.
  virtual bool predictEntries(const std::vector<Camera>& history,
                              std::vector<int64_t>& entries) const {
    (void)history;
    (void)entries;
    return false;
  }
};

/// Never predicts: no prefetching.
class NoPredictor : public Predictor {
 public:
  const char* name() const override { return "none"; }
  bool predict(const std::vector<Camera>&, Camera&) const override { return false; }
};

/// Linear extrapolation of the last two poses: eye, forward and up continue by the same step.
class LinearPredictor : public Predictor {
 public:
  const char* name() const override { return "linear"; }
  bool predict(const std::vector<Camera>& history, Camera& next) const override;
};

/// The user is now at `pose`: appends its trajectory camera (width x height) to `history`, keeps
/// the last kPredictorHistory, and returns the pose of the predicted next camera, or `pose` itself
/// when the predictor makes no prediction (the user is taken to stay). How `afam predict` and the
/// tests score a predictor on a trajectory.
Pose predictNextPose(const Predictor& predictor, std::vector<Camera>& history, const Pose& pose,
                     int width = 256, int height = 256);

}  // namespace afam
