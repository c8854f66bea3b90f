// SPDX-License-Identifier: BSD-3-Clause
// Next-pose prediction: the part of a prefetcher that guesses where the user looks next. Every
// predictor sees the points of view in order (observe) and is asked for the next one (predictNext).
// Block-level prefetchers (APPA's table, ForeCache's signature model) sit on top of these in
// prefetch_predictors.hpp; `afam predict` uses only this interface.
//
// Positions live in the normalised frame (volume in [-1, 1]^3), as in camera.hpp:
//   eye = distance * (sin t cos p, sin t sin p, cos t).
#pragma once

#include <cstddef>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "afam/camera.hpp"

namespace afam {

/// Eye position of a pose in the normalised frame.
Vec3 posePosition(const Pose& p);
/// The pose whose eye is at `eye` (phi in [0, 360), theta in [0, 180]); eye = 0 gives distance 0.
Pose poseFromPosition(const Vec3& eye);
/// Euclidean distance between the eye positions of two poses.
double poseDistance(const Pose& a, const Pose& b);

/// Writes poses in the trajectory format of camera.hpp (3 N float32: distances, theta, phi),
/// to a temporary file renamed into place. Throws IoError.
void writeTrajectory(const std::string& path, const std::vector<Pose>& poses);

class PosePredictor {
 public:
  virtual ~PosePredictor() = default;
  virtual std::string name() const = 0;
  /// Forget the history (a new trajectory starts).
  virtual void reset() = 0;
  /// The user is now at `pose` (called once per point of view, in order).
  virtual void observe(const Pose& pose) = 0;
  /// The predicted next point of view. Before any observe() it returns a default Pose.
  virtual Pose predictNext() const = 0;
};

/// Shared bookkeeping: the last `capacity` poses.
class HistoryPosePredictor : public PosePredictor {
 public:
  explicit HistoryPosePredictor(std::size_t capacity) : capacity_(capacity < 2 ? 2 : capacity) {}
  void reset() override { history_.clear(); }
  void observe(const Pose& pose) override {
    history_.push_back(pose);
    while (history_.size() > capacity_) history_.pop_front();
  }
  const std::deque<Pose>& history() const { return history_; }

 private:
  std::size_t capacity_;
  std::deque<Pose> history_;
};

/// "none": the next pose is the current one.
class StayPosePredictor : public HistoryPosePredictor {
 public:
  StayPosePredictor() : HistoryPosePredictor(2) {}
  std::string name() const override { return "none"; }
  Pose predictNext() const override;
};

/// "linear": last-pose linear extrapolation of the eye position, P_{n+1} = 2 P_n - P_{n-1}.
class LinearPosePredictor : public HistoryPosePredictor {
 public:
  LinearPosePredictor() : HistoryPosePredictor(2) {}
  std::string name() const override { return "linear"; }
  Pose predictNext() const override;
};

/// Options the factory passes on to the predictors that need them.
struct PosePredictorOptions {
  std::string lstmWeights;  ///< empty: defaultLstmWeightsPath()
};

/// none | linear | appa | forecache | lstm. Throws InvalidArgument for other names, and whatever
/// the predictor's loader throws (a missing or corrupt LSTM weights file, for example).
std::unique_ptr<PosePredictor> makePosePredictor(const std::string& name,
                                                 const PosePredictorOptions& options = {});

}  // namespace afam
