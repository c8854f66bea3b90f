// SPDX-License-Identifier: BSD-3-Clause
// Prefetching: a predictor of the next point of view and a thread that loads the blocks that view
// will need into the RAM cache while the current frame renders (the paper's Algorithm 3).
//
// Protocol (the paper's rendering_done flag, with proper synchronisation): the frame thread calls
// start(job) just before it renders; the prefetch thread wakes on a condition variable and runs the
// job, which plans the predicted blocks and loads them one by one, checking an atomic stop flag
// between block loads. The frame thread calls finish() as soon as rendering is done: it sets the
// flag and waits (condition variable, no spinning) until the job has returned, which takes at most
// one block load. The thread then sleeps until the next start().
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "afam/cache.hpp"
#include "afam/camera.hpp"

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

struct PrefetchStats {
  uint64_t jobs = 0, blocksLoaded = 0, stoppedEarly = 0;
};

class Prefetcher {
 public:
  /// A job gets the stop flag and must check it between block loads.
  using Job = std::function<void(const std::atomic<bool>& stop, uint64_t& loaded)>;

  Prefetcher();
  ~Prefetcher();  ///< stops and joins the thread
  Prefetcher(const Prefetcher&) = delete;
  Prefetcher& operator=(const Prefetcher&) = delete;

  /// Hands a job to the thread (a job still running is stopped first).
  void start(Job job);
  /// Sets the stop flag and blocks until the running job (if any) has returned.
  void finish();
  bool busy() const;
  PrefetchStats stats() const;

  /// Convenience job: loads `entries` in order through cache.prefetch until stopped.
  static Job loadJob(LruCache& cache, std::vector<int64_t> entries);

 private:
  void run();
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  Job job_;
  bool hasJob_ = false, running_ = false, quit_ = false;
  std::atomic<bool> stop_{false};
  PrefetchStats stats_;
  std::thread thread_;
};

}  // namespace afam
