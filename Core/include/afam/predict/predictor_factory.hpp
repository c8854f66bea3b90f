// SPDX-License-Identifier: BSD-3-Clause
// The one factory of the predictors (prefetch.hpp's Predictor): none and linear (prefetch.hpp),
// lstm (lstm.hpp) and the data-aware appa and forecache, run live in the renderer's prefetch
// thread and by `afam predict`.
//
// The renderer calls predict(history, next) (or predictEntries) once per frame in the prefetch
// thread, with its bounded history of cameras; ForeCache learns from the cameras it has not seen
// yet and starts over when the history does not continue the previous one. Predictors that know
// the blocks to fetch without a visibility computation (APPA's table, ForeCache's signature
// ranking) also override Predictor::predictEntries; the renderer's prefetch job asks for the
// entries first and falls back to selecting the predicted camera's view.
#pragma once

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "afam/predict/appa.hpp"
#include "afam/predict/forecache.hpp"
#include "afam/predict/predictor.hpp"
#include "afam/scene/lod.hpp"

namespace afam {

/// What the data-aware predictors need to know about the scene.
struct PredictorContext {
  std::shared_ptr<const AfamFile> file;
  LodOptions lod;
  std::vector<float> tfTable;  ///< the renderer's TF table (TF culling) over [tfLo, tfHi]
  double tfLo = 0, tfHi = 1;
  std::string lstmWeights;  ///< empty: defaultLstmWeightsPath()
  AppaGrid appaGrid;
  std::string appaTablePath;  ///< empty: FILE.afam.appa
  int appaThreads = 1;
  AppaBuildReport* appaReport = nullptr;  ///< filled when the APPA table is loaded or built
};

/// The one factory of the predictors: none | linear | lstm (camera only) | appa | forecache (these
/// use ctx.file when it is set: without a file appa predicts the parent POV but no blocks, and
/// forecache runs without its signature model). Throws InvalidArgument for other names, and
/// whatever a loader throws (a missing or corrupt LSTM weights file, for example).
std::unique_ptr<Predictor> makePrefetchPredictor(const std::string& name,
                                                 const PredictorContext& ctx = {});

/// The names makePrefetchPredictor takes, in the order the command line lists them.
const std::vector<std::string>& predictorNames();

/// "appa": the next point of view is the parent POV (the sample pose of the last pose's cell); with
/// a table, its blocks are the ones the table stores for that cell.
class AppaPredictor : public Predictor {
 public:
  explicit AppaPredictor(AppaGrid grid) : grid_(grid) {}
  explicit AppaPredictor(AppaTable table)
      : grid_(table.grid()), table_(std::move(table)), hasTable_(true) {}
  const char* name() const override { return "appa"; }
  /// The parent POV's camera (what the table stores blocks for).
  bool predict(const std::vector<Camera>& history, Camera& next) const override;
  /// False without a table.
  bool predictEntries(const std::vector<Camera>& history,
                      std::vector<int64_t>& entries) const override;
  const AppaTable& table() const { return table_; }

 private:
  AppaGrid grid_;
  AppaTable table_;
  bool hasTable_ = false;
};

/// "forecache": ForeCacheModel fed with the history's cameras; with a file, its signature model
/// sees the blocks each pose selects, and predictEntries ranks them.
class ForeCachePredictor : public Predictor {
 public:
  explicit ForeCachePredictor(const PredictorContext& ctx, const ForeCacheOptions& options = {});
  const char* name() const override { return "forecache"; }
  bool predict(const std::vector<Camera>& history, Camera& next) const override;
  /// False without a file.
  bool predictEntries(const std::vector<Camera>& history,
                      std::vector<int64_t>& entries) const override;
  ForeCachePhase phase() const;

 private:
  /// Feeds the model the cameras of `history` not seen at the previous call (all of them, after a
  /// reset, when the history does not continue the previous one). Caller holds mutex_.
  void update(const std::vector<Camera>& history) const;
  AppaTable::VisibleFn visible_;
  mutable std::mutex mutex_;
  mutable ForeCacheModel model_;
  mutable std::vector<Vec3> seen_;
};

/// Signature of a file entry for ForeCache's SB model: mean value and value range (both relative
/// to the file's range), log2 of the control-point count / 15, RMSE relative to the range.
BlockSignature entrySignature(const AfamFile& file, int64_t entry);

}  // namespace afam
