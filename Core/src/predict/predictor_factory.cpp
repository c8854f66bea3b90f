// SPDX-License-Identifier: BSD-3-Clause
#include "afam/predict/predictor_factory.hpp"

#include <cmath>
#include <unordered_set>

#include "afam/base/errors.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/predict/lstm.hpp"

namespace afam {

namespace {
Pose poseOf(const Camera& c) { return poseFromPosition(c.eye); }

std::string appaContext(const PredictorContext& ctx) {
  // Everything that changes which blocks a pose sees.
  std::string s = "lod:" + std::to_string(int(ctx.lod.policy)) + ":" +
                  std::to_string(ctx.lod.bandWidth) + ":" + std::to_string(ctx.lod.pixelBudget) +
                  ":" + std::to_string(ctx.lod.frustumCulling) + ":" +
                  std::to_string(ctx.lod.tfCulling) + ";tf:" + std::to_string(ctx.tfLo) + ":" +
                  std::to_string(ctx.tfHi) + ":";
  const uint64_t tfHash = fnv1a64(ctx.tfTable.data(), ctx.tfTable.size() * sizeof(float));
  return s + std::to_string(tfHash) + ";camera:fromPose-256";
}
}  // namespace

const std::vector<std::string>& predictorNames() {
  static const std::vector<std::string> names = {"none", "linear", "appa", "forecache", "lstm"};
  return names;
}

BlockSignature entrySignature(const AfamFile& file, int64_t entry) {
  const ModelEntry& e = file.entries().at(static_cast<std::size_t>(entry));
  const VolumeHeader& h = file.header();
  const double lo = h.valueMin, range = h.valueMax > h.valueMin ? h.valueMax - h.valueMin : 1.0;
  const double ncp = double(e.ncp[0]) * e.ncp[1] * e.ncp[2];
  return {float((0.5 * (e.minValue + e.maxValue) - lo) / range),
          float((e.maxValue - e.minValue) / range), float(std::log2(std::max(1.0, ncp)) / 15.0),
          float(e.rmse / range)};
}

namespace {
std::unique_ptr<Predictor> makeAppa(const PredictorContext& ctx) {
  if (!ctx.file) return std::make_unique<AppaPredictor>(ctx.appaGrid);
  const LodSelector selector(ctx.lod);
  const auto visible =
      makeLodVisibleFn(ctx.file, selector, 256, 256, ctx.tfTable, ctx.tfLo, ctx.tfHi);
  const std::string path =
      ctx.appaTablePath.empty() ? ctx.file->path() + ".appa" : ctx.appaTablePath;
  AppaTable table = AppaTable::loadOrBuild(path, appaSourceKey(*ctx.file, appaContext(ctx)),
                                           ctx.appaGrid, visible, ctx.appaReport, ctx.appaThreads);
  return std::make_unique<AppaPredictor>(std::move(table));
}
}  // namespace

std::unique_ptr<Predictor> makePrefetchPredictor(const std::string& name,
                                                 const PredictorContext& ctx) {
  if (name == "none") return std::make_unique<NoPredictor>();
  if (name == "linear") return std::make_unique<LinearPredictor>();
  if (name == "lstm")
    return std::make_unique<LstmPredictor>(ctx.lstmWeights.empty() ? defaultLstmWeightsPath()
                                                                   : ctx.lstmWeights);
  if (name == "appa") return makeAppa(ctx);
  if (name == "forecache") return std::make_unique<ForeCachePredictor>(ctx);
  throw InvalidArgument("unknown predictor '" + name +
                        "' (expected none, linear, appa, forecache or lstm)");
}

bool AppaPredictor::predict(const std::vector<Camera>& history, Camera& next) const {
  if (history.empty()) return false;
  const Camera& last = history.back();
  const Pose p = grid_.samplePose(grid_.cellOf(poseOf(last)));
  next = Camera::fromPose(p, last.width, last.height);
  return true;
}

bool AppaPredictor::predictEntries(const std::vector<Camera>& history,
                                   std::vector<int64_t>& entries) const {
  if (!hasTable_ || history.empty()) return false;
  auto [b, e] = table_.lookup(poseOf(history.back()));
  entries.assign(b, e);
  return true;
}

namespace {
ForeCacheDataSource foreCacheData(const PredictorContext& ctx,
                                  const AppaTable::VisibleFn& visible) {
  ForeCacheDataSource data;
  if (!ctx.file) return data;
  data.visibleBlocks = visible;
  std::shared_ptr<const AfamFile> file = ctx.file;
  data.signature = [file](int64_t entry) { return entrySignature(*file, entry); };
  return data;
}

AppaTable::VisibleFn foreCacheVisible(const PredictorContext& ctx) {
  if (!ctx.file) return nullptr;
  const LodSelector selector(ctx.lod);
  return makeLodVisibleFn(ctx.file, selector, 256, 256, ctx.tfTable, ctx.tfLo, ctx.tfHi);
}

/// How many cameras at the end of `history` are new after `seen` (the eyes of the previous call's
/// history): the fewest such that the rest continues `seen`; all of them when none does.
std::size_t unseenCameras(const std::vector<Camera>& history, const std::vector<Vec3>& seen) {
  const std::size_t n = history.size();
  for (std::size_t m = 1; m <= n; ++m) {
    const std::size_t keep = n - m;
    if (keep > seen.size()) continue;
    bool same = true;
    for (std::size_t i = 0; i < keep && same; ++i)
      same = history[i].eye == seen[seen.size() - keep + i];
    if (same) return m;
  }
  return n;
}
}  // namespace

ForeCachePredictor::ForeCachePredictor(const PredictorContext& ctx, const ForeCacheOptions& options)
    : visible_(foreCacheVisible(ctx)), model_(options, foreCacheData(ctx, visible_)) {}

ForeCachePhase ForeCachePredictor::phase() const {
  std::lock_guard<std::mutex> g(mutex_);
  return model_.phase();
}

void ForeCachePredictor::update(const std::vector<Camera>& history) const {
  // The renderer's history is bounded and a frame's job may be dropped before it runs (a very fast
  // frame), so align the history with the cameras already seen and feed only the new ones.
  const std::size_t n = history.size(), fresh = unseenCameras(history, seen_);
  if (fresh == n) model_.reset();  // a new trajectory (or no overlap with what was seen)
  for (std::size_t i = n - fresh; i < n; ++i) model_.observe(poseOf(history[i]));
  seen_.clear();
  for (const Camera& c : history) seen_.push_back(c.eye);
}

bool ForeCachePredictor::predict(const std::vector<Camera>& history, Camera& next) const {
  if (history.empty()) return false;
  std::lock_guard<std::mutex> g(mutex_);
  update(history);
  if (history.size() < 2) return false;
  const Camera& last = history.back();
  next = Camera::fromPose(model_.predictNext(), last.width, last.height);
  return true;
}

bool ForeCachePredictor::predictEntries(const std::vector<Camera>& history,
                                        std::vector<int64_t>& entries) const {
  if (!visible_ || history.empty()) return false;
  std::lock_guard<std::mutex> g(mutex_);
  update(history);
  entries.clear();
  if (history.size() < 2) return true;  // learnt from it; nothing to predict yet
  const std::vector<Pose> cands = model_.candidatePoses(2);
  entries = visible_(cands.front());
  std::unordered_set<int64_t> have(entries.begin(), entries.end());
  if (model_.phase() == ForeCachePhase::Sensemaking && cands.size() > 1) {
    // SB: the blocks the other likely views would add, most similar to the dwell signature first.
    std::vector<int64_t> extra;
    for (int64_t e : visible_(cands[1]))
      if (!have.count(e)) extra.push_back(e);
    for (int64_t e : model_.rankBySignature(extra)) entries.push_back(e);
  } else {
    // AB: the Markov chain's second most likely move next.
    for (std::size_t i = 1; i < cands.size(); ++i)
      for (int64_t e : visible_(cands[i]))
        if (have.insert(e).second) entries.push_back(e);
  }
  return true;
}

}  // namespace afam
