// SPDX-License-Identifier: BSD-3-Clause
// The renderer's predictors and their one factory: none and linear (prefetch.hpp) and the
// data-aware appa, forecache and lstm, run live in the prefetch thread.
//
// The renderer calls predict(history, next) (or predictEntries) once per frame in the prefetch
// thread, with its bounded history of cameras; the stateful predictors here learn from the cameras
// they have not seen yet and start over when the history does not continue the previous one.
// Predictors that know the blocks to fetch without a visibility computation (APPA's table,
// ForeCache's signature ranking) also override Predictor::predictEntries; the renderer's prefetch
// job asks for the entries first and falls back to selecting the predicted camera's view.
#pragma once

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "afam/lod.hpp"
#include "afam/predictors/appa.hpp"
#include "afam/predictors/forecache.hpp"
#include "afam/predictors/pose_predictor.hpp"
#include "afam/prefetch.hpp"

namespace afam {

/// What the data-aware predictors need to know about the scene.
struct PredictorContext {
  std::shared_ptr<const AfamFile> file;
  LodOptions lod;
  std::vector<float> tfTable;  ///< the renderer's TF table (TF culling) over [tfLo, tfHi]
  double tfLo = 0, tfHi = 1;
  std::string lstmWeights;      ///< empty: defaultLstmWeightsPath()
  AppaGrid appaGrid;
  std::string appaTablePath;    ///< empty: FILE.afam.appa
  int appaThreads = 1;
  AppaBuildReport* appaReport = nullptr;  ///< filled when the APPA table is loaded or built
};

/// The one factory of the renderer's predictors: none | linear (camera only) | appa | forecache |
/// lstm (these use ctx). Throws InvalidArgument for other names or when appa/forecache get no
/// file, and whatever a loader throws (a missing or corrupt LSTM weights file, for example).
std::unique_ptr<Predictor> makePrefetchPredictor(const std::string& name, const PredictorContext& ctx = {});

/// The names makePrefetchPredictor takes, in the order the command line lists them.
const std::vector<std::string>& predictorNames();

/// A PosePredictor behind the camera interface (lstm; forecache without data).
class PosePredictorAdapter : public Predictor {
 public:
  explicit PosePredictorAdapter(std::unique_ptr<PosePredictor> pose) : pose_(std::move(pose)) {}
  const char* name() const override { return name_.c_str(); }
  bool predict(const std::vector<Camera>& history, Camera& next) const override;

 protected:
  /// Feeds the cameras of `history` not seen at the previous call (all of them, after a reset,
  /// when the history does not continue the previous one). Caller holds mutex_.
  void update(const std::vector<Camera>& history) const;
  std::unique_ptr<PosePredictor> pose_;
  std::string name_ = pose_ ? pose_->name() : std::string("?");
  mutable std::mutex mutex_;
  mutable std::vector<Vec3> seen_;
};

class AppaPredictor : public Predictor {
 public:
  AppaPredictor(AppaTable table) : table_(std::move(table)) {}
  const char* name() const override { return "appa"; }
  /// The parent POV's camera (what the table stores blocks for).
  bool predict(const std::vector<Camera>& history, Camera& next) const override;
  bool predictEntries(const std::vector<Camera>& history, std::vector<int64_t>& entries) const override;
  const AppaTable& table() const { return table_; }

 private:
  AppaTable table_;
};

class ForeCachePredictor : public PosePredictorAdapter {
 public:
  ForeCachePredictor(const PredictorContext& ctx, const ForeCacheOptions& options = {});
  bool predictEntries(const std::vector<Camera>& history, std::vector<int64_t>& entries) const override;
  ForeCachePhase phase() const;

 private:
  AppaTable::VisibleFn visible_;
};

/// Signature of a file entry for ForeCache's SB model: mean value and value range (both relative
/// to the file's range), log2 of the control-point count / 15, RMSE relative to the range.
BlockSignature entrySignature(const AfamFile& file, int64_t entry);

}  // namespace afam
