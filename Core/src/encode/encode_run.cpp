// SPDX-License-Identifier: BSD-3-Clause
#include "afam/encode/encode_run.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <set>
#include <sstream>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/base/huge_pages.hpp"
#include "afam/base/seconds_since.hpp"
#include "afam/encode/first_step_blocks.hpp"
#include "afam/format/block_decode.hpp"
#include "afam/format/run_writer.hpp"
#include "block_encoding.hpp"
#include "step_records.hpp"

namespace afam {

FirstStepBlocks::FirstStepBlocks() = default;
FirstStepBlocks::~FirstStepBlocks() = default;

void FirstStepBlocks::startTaking() {
  std::lock_guard<std::mutex> lock(mutex_);
  taking_ = true;
}

int64_t FirstStepBlocks::kept() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return kept_;
}

int64_t FirstStepBlocks::taken() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return taken_;
}

namespace {

/// What encodeBlock decided for a block (not its samples or its search's questions).
void copyOutcome(const BlockTask& from, BlockTask& to) {
  to.mask = from.mask;
  to.entry = from.entry;
  to.stored = from.stored;
  to.ncpStar = from.ncpStar;
  to.complex = from.complex;
  to.exact = from.exact;
  to.reducedDegree = from.reducedDegree;
  to.rmse = from.rmse;
  to.maxError = from.maxError;
}

}  // namespace

void FirstStepBlocks::keep(int level, double bound, const BlockTask& t) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (taking_) return;  // the run's blocks that were not taken: nothing to copy
  }
  auto kept = std::make_unique<BlockTask>();
  copyOutcome(t, *kept);
  std::lock_guard<std::mutex> lock(mutex_);
  const Key key{level, t.ijk[0], t.ijk[1], t.ijk[2], bound, t.search};
  if (blocks_.emplace(key, std::move(kept)).second) ++kept_;
}

bool FirstStepBlocks::take(int level, double bound, BlockTask& t) {
  std::unique_ptr<BlockTask> kept;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!taking_) return false;
    const auto it = blocks_.find(Key{level, t.ijk[0], t.ijk[1], t.ijk[2], bound, t.search});
    if (it == blocks_.end()) return false;
    kept = std::move(it->second);
    blocks_.erase(it);
    ++taken_;
  }
  copyOutcome(*kept, t);
  t.fits = 0;  // none this time
  return true;
}

namespace {

/// What a run's steps share: the first step's grid and sample size.
struct StepGrid {
  Index3 dims{};
  std::array<double, 3> origin{}, spacing{};
  int bytesPerVoxel = 0;
  explicit StepGrid(const VolumeSource& s)
      : dims(s.dims()),
        origin(s.origin()),
        spacing(s.spacing()),
        bytesPerVoxel(s.bytesPerVoxel()) {}
};

/// The first place where a step's grid differs from the run's, or empty.
std::string gridDifference(const StepGrid& first, const VolumeSource& step) {
  std::ostringstream d;
  const Index3 a = first.dims, b = step.dims();
  if (a != b) {
    d << "dims " << b[0] << "x" << b[1] << "x" << b[2] << " differ from the first step's " << a[0]
      << "x" << a[1] << "x" << a[2];
  } else if (first.origin != step.origin()) {
    d << "origin differs from the first step's";
  } else if (first.spacing != step.spacing()) {
    d << "spacing differs from the first step's";
  } else if (first.bytesPerVoxel != step.bytesPerVoxel()) {
    d << "sample type (" << step.bytesPerVoxel() << " bytes) differs from the first step's ("
      << first.bytesPerVoxel << " bytes)";
  }
  return d.str();
}

/// A step whose range the run's first pass already found: the encoder does not read it again for
/// that (VolumeSource::knownRange).
class RangedStep : public VolumeSource {
 public:
  RangedStep(VolumeSource& s, double lo, double hi, bool missing)
      : s_(s), lo_(lo), hi_(hi), missing_(missing) {}
  Index3 dims() const override { return s_.dims(); }
  std::array<double, 3> origin() const override { return s_.origin(); }
  std::array<double, 3> spacing() const override { return s_.spacing(); }
  std::string name() const override { return s_.name(); }
  void readSlab(int64_t z0, int64_t zCount, float* out) override { s_.readSlab(z0, zCount, out); }
  void readRows(int64_t z0, int64_t zCount, int64_t y0, int64_t yCount, float* out) override {
    s_.readRows(z0, zCount, y0, yCount, out);
  }
  std::optional<SampleType> storedType() const override { return s_.storedType(); }
  void readStoredRows(int64_t z0, int64_t zCount, int64_t y0, int64_t yCount, void* out) override {
    s_.readStoredRows(z0, zCount, y0, yCount, out);
  }
  bool knownRange(double& lo, double& hi) const override {
    lo = lo_;
    hi = hi_;
    return true;
  }
  bool knownMissing() const override { return missing_; }
  int bytesPerVoxel() const override { return s_.bytesPerVoxel(); }
  bool readsOnCallingThread() const override { return s_.readsOnCallingThread(); }
  bool concurrentReads() const override { return s_.concurrentReads(); }

 private:
  VolumeSource& s_;
  double lo_, hi_;
  bool missing_;
};

/// Where one step's models go: the run writer, references included. The writer is made at the
/// first step's begin(), with the run's range and bound, or, when the run has none yet
/// (`run` null), the first step's own range and the bound the encoder derived from it; missing
/// samples as `declared` says (RunEncoder::expectMissingSamples) or the first step has them.
class StepSink : public ModelSink {
 public:
  StepSink(std::unique_ptr<RunWriter>& writer, const std::string& path, const VolumeHeader* run,
           const VolumeHeader& declared, int keyInterval, double bound, double time,
           std::map<std::pair<int, Int3>, uint64_t>* blockBytes = nullptr)
      : writer_(writer),
        path_(path),
        run_(run),
        declared_(declared),
        keyInterval_(keyInterval),
        bound_(bound),
        time_(time),
        blockBytes_(blockBytes) {}
  void begin(const VolumeHeader& h) override {
    if (!writer_) {
      VolumeHeader header = h;  // the step's partition, with the run's range and bound
      double bound = bound_;
      if (declared_.missing != MissingKind::None) {
        header.missing = declared_.missing;
        header.missingValue = declared_.missingValue;
      }
      if (run_) {
        header.valueMin = run_->valueMin;
        header.valueMax = run_->valueMax;
        header.errorBound = run_->errorBound;
        header.relativeBound = run_->relativeBound;
      } else {  // as encodeVolume derived it from the step's range
        bound = absoluteBound(h);
      }
      writer_ = std::make_unique<RunWriter>(path_, header, keyInterval_, bound);
    }
    if (h.missing != MissingKind::None && writer_->header().missing == MissingKind::None)
      throw InvalidArgument(
          "encode: the step at time " + std::to_string(time_) +
          " has missing samples (NaN), and the run was written without: encode the run whole "
          "(afam encode IN0 IN1 ... OUT), which marks it from the first step on");
    stepMin_ = h.valueMin;
    stepMax_ = h.valueMax;
    writer_->beginStep(time_);
  }
  void add(const ModelEntry& e, const void* stored) override {
    if (blockBytes_ && !e.reference) (*blockBytes_)[{e.level, e.block}] += e.storedSize;
    if (e.reference) {
      writer_->addReference(e);
      ++references;
    } else if (e.residual) {
      writer_->addResidual(e, stored);
      ++residuals;
    } else {
      writer_->addStored(e, stored);
    }
  }
  void end() { writer_->endStep(float(stepMin_), float(stepMax_)); }
  int64_t references = 0, residuals = 0;

 private:
  std::unique_ptr<RunWriter>& writer_;
  std::string path_;
  const VolumeHeader* run_;
  const VolumeHeader& declared_;
  int keyInterval_;
  double bound_, time_, stepMin_ = 0, stepMax_ = 0;
  std::map<std::pair<int, Int3>, uint64_t>* blockBytes_;
};

/// Each block's model as decoded on its samples, kept while the block keeps the model: one buffer
/// on huge pages (the first touch of ~600 MB in 4 KB pages cost a 512^3 run's first step 1.4 s on a
/// VM), a block's place in it fixed by its slot; the blocks beyond kBytes (in slot order) are not
/// kept. A slot is used by one thread at a time (PreviousStep).
class DecodedValues {
 public:
  /// At most this many bytes of decoded samples are kept (a 512^3 float32 run's blocks hold about
  /// 600 MB); a block beyond it is decoded and evaluated at every step.
  static constexpr size_t kBytes = size_t(2) << 30;

  explicit DecodedValues(const Partition& part) {
    for (int l = 0; l < part.levels(); ++l)
      for (int64_t b = 0; b < part.blockCount(l); ++b) {
        const Int3 n = part.extent(l, part.blockFromLinear(l, b)).samples;
        const size_t count = size_t(n[0]) * size_t(n[1]) * size_t(n[2]);
        const size_t first = slots_.empty() ? 0 : slots_.back().first + slots_.back().count;
        slots_.push_back({first, (first + count) * sizeof(float) <= kBytes ? count : 0});
      }
    // Mapped, not touched: a page is faulted in when a block is first kept there.
    if (!slots_.empty()) buffer_.resize(slots_.back().first + slots_.back().count);
  }
  /// The slot's values when they were kept for `key`, else nullptr.
  const float* find(size_t slot, uint64_t key) const {
    const Slot& s = slots_.at(slot);
    return s.held && s.key == key ? buffer_.data() + s.first : nullptr;
  }
  /// Keeps `values` (the block's sample count of them) for `key` where the slot has room.
  void put(size_t slot, uint64_t key, const std::vector<float>& values) {
    Slot& s = slots_.at(slot);
    s.held = false;
    if (s.count == 0 || values.size() != s.count) return;
    std::copy(values.begin(), values.end(), buffer_.begin() + std::ptrdiff_t(s.first));
    s.key = key;
    s.held = true;
  }

 private:
  struct Slot {
    size_t first = 0, count = 0;  ///< where in the buffer, how many (0: not kept)
    uint64_t key = 0;
    bool held = false;
  };
  std::vector<Slot> slots_;
  HugePageVector<float> buffer_;
};

/// The step before's models, read back from the run being written; each block's model as decoded
/// on its samples kept while the block keeps it (PreviousStep::values, DecodedValues).
class WrittenStep : public PreviousStep {
 public:
  explicit WrittenStep(const RunWriter& writer) : writer_(writer), values_(writer.partition()) {}
  bool entry(int level, Int3 block, ModelEntry& entry, bool& mayRefer) const override {
    if (writer_.stepsDone() == 0) return false;
    mayRefer = writer_.canReference(level, block);
    return !mayRefer || writer_.previousEntry(level, block, entry);
  }
  void control(int level, Int3 block, const ModelEntry& entry, FitResult& model) const override {
    ModelEntry owner;
    if (!writer_.previousModel(level, block, owner, model.control) || owner.offset != entry.offset)
      throw InvalidArgument("encode: " + Partition::blockName(level, block) +
                            " has no model at the step before to code against");
    model.ncp = entry.ncp;
    model.degree = entry.degree;
  }
  void values(int level, Int3 block, const ModelEntry& entry,
              const std::function<void(const float*, size_t)>& use) const override {
    // A payload's offset names its model (a reference keeps its owner's).
    const size_t slot = writer_.modelSlot(level, block);
    const size_t count = size_t(entry.samples[0]) * entry.samples[1] * entry.samples[2];
    if (const float* kept = values_.find(slot, entry.offset)) return use(kept, count);
    thread_local FitResult model;
    thread_local std::vector<float> decoded;
    control(level, block, entry, model);
    decodeBlockSamples(entry, model.control.data(), EncodingMode::Adaptive, decoded);
    decodedCount_.fetch_add(1, std::memory_order_relaxed);
    values_.put(slot, entry.offset, decoded);
    use(decoded.data(), decoded.size());
  }
  /// Blocks whose model values() decoded since the last call (not kept).
  int64_t takeDecodedCount() { return decodedCount_.exchange(0, std::memory_order_relaxed); }

 private:
  const RunWriter& writer_;
  mutable DecodedValues values_;
  mutable std::atomic<int64_t> decodedCount_{0};
};

}  // namespace

struct RunEncoder::State {
  std::string path;
  EncoderOptions options;   ///< every step held to the run's bound, in data units
  VolumeHeader header;      ///< the run's range and bound as given
  bool rangeKnown = false;  ///< false: the first step's range is the run's
  int keyInterval = 16;
  double bound = 0;
  double lastTime = std::numeric_limits<double>::quiet_NaN();
  std::unique_ptr<StepGrid> grid;
  std::unique_ptr<RunWriter> writer;  ///< the run; on a team's other processes, their scratch run
  std::unique_ptr<WrittenStep> previous;
  RunStats stats;
  std::chrono::steady_clock::time_point start;
};

RunEncoder::RunEncoder(const std::string& path, const EncoderOptions& options, int keyInterval)
    : s_(std::make_unique<State>()) {
  if (keyInterval < 1)
    throw InvalidArgument("encode: key interval " + std::to_string(keyInterval) + " < 1");
  State& s = *s_;
  s.start = std::chrono::steady_clock::now();
  s.path = path;
  s.keyInterval = keyInterval;
  s.options = options;
  s.options.runStep = true;
  if (keyInterval == 1) s.options.runCodedShare = 1.0;  // no step may refer to another
  s.header.errorBound = options.errorBound;
  s.header.relativeBound = options.relativeBound;
}

RunEncoder::RunEncoder(const std::string& path, const EncoderOptions& options, int keyInterval,
                       double valueMin, double valueMax)
    : RunEncoder(path, options, keyInterval) {
  if (!(valueMin <= valueMax) || !std::isfinite(valueMin) || !std::isfinite(valueMax))
    throw InvalidArgument("encode: the run's value range must be finite");
  State& s = *s_;
  s.rangeKnown = true;
  s.bound = options.relativeBound ? options.errorBound * (valueMax - valueMin) : options.errorBound;
  s.header.valueMin = valueMin;
  s.header.valueMax = valueMax;
  s.options.errorBound = s.bound;
  s.options.relativeBound = false;
  s.stats.valueMin = valueMin;
  s.stats.valueMax = valueMax;
  s.stats.bound = s.bound;
}

RunEncoder::~RunEncoder() = default;

EncodeStats RunEncoder::addStep(VolumeSource& step, double time) {
  SoloTeam solo;
  return addStep(step, time, solo);
}

EncodeStats RunEncoder::addStep(VolumeSource& step, double time, EncodeTeam& team) {
  State& s = *s_;
  const int64_t k = static_cast<int64_t>(s.stats.steps.size());
  teamStep(team, [&] {  // a team refuses the step together
    if (!std::isfinite(time) || (k > 0 && !(time > s.lastTime)))
      throw InvalidArgument("encode: time values must increase: step " + std::to_string(k) +
                            " has " + std::to_string(time));
    if (!s.grid) s.grid = std::make_unique<StepGrid>(step);
    const std::string d = gridDifference(*s.grid, step);
    if (!d.empty())
      throw InvalidArgument("encode: step " + std::to_string(k) + " (" + step.name() + "): " + d);
  });
  // The first process writes the run; the others, a scratch run of their own (never committed).
  const bool writes = team.rank() == 0;
  const std::string path = writes ? s.path : s.path + ".rank" + std::to_string(team.rank());
  StepSink sink(s.writer, path, s.rangeKnown ? &s.header : nullptr, s.header, s.keyInterval,
                s.bound, time, writes ? &s.stats.blockBytes : nullptr);
  StepRecorder recorder(sink);
  s.options.previous = s.previous.get();
  const EncodeStats stats = encodeVolume(
      step, s.options, team.size() > 1 ? static_cast<ModelSink&>(recorder) : sink, team);
  std::vector<uint8_t> models;  // the step as the first process wrote it, for the others
  teamStep(team, [&] {
    if (!writes) return;
    sink.end();
    models = recorder.bytes();
  });
  if (team.size() > 1) {
    team.broadcastFromFirst(models);
    teamStep(team, [&] {
      if (writes) return;
      replayStep(models, sink);
      sink.end();
    });
  }
  if (!s.rangeKnown) {  // the first step's range and bound are the run's from now on
    s.rangeKnown = true;
    s.bound = stats.bound;
    s.header.valueMin = stats.valueMin;
    s.header.valueMax = stats.valueMax;
    s.options.errorBound = s.bound;
    s.options.relativeBound = false;
    s.stats.valueMin = stats.valueMin;
    s.stats.valueMax = stats.valueMax;
    s.stats.bound = s.bound;
  }
  s.lastTime = time;
  s.stats.steps.push_back(stats);
  s.stats.references.push_back(sink.references);
  s.stats.residuals.push_back(sink.residuals);
  s.stats.decodedBefore.push_back(s.previous ? s.previous->takeDecodedCount() : 0);
  if (!s.previous) s.previous = std::make_unique<WrittenStep>(*s.writer);
  return s.stats.steps.back();
}

void RunEncoder::expectMissingSamples() {
  State& s = *s_;
  if (s.writer) throw InvalidArgument("encode: missing samples are declared before the first step");
  s.header.missing = s.options.hasMissingValue ? MissingKind::Value : MissingKind::NaN;
  s.header.missingValue = s.options.hasMissingValue ? s.options.missingValue : 0.0;
}

void RunEncoder::setProgress(std::function<bool(double)> progress) {
  s_->options.progress = std::move(progress);
}

const RunStats& RunEncoder::stepStats() const { return s_->stats; }

RunStats RunEncoder::commit() {
  SoloTeam solo;
  return commit(solo);
}

RunStats RunEncoder::commit(EncodeTeam& team) {
  State& s = *s_;
  if (!s.writer) throw InvalidArgument("encode: a run needs at least one step");
  teamStep(team, [&] {
    if (team.rank() == 0) s.stats.bytesOut = s.writer->commit();
  });
  if (team.rank() != 0) {  // the scratch run and its temporary file go
    s.previous.reset();
    s.writer.reset();
  }
  s.stats.seconds = secondsSince(s.start);
  return s.stats;
}

namespace {

/// Bytes of each block over the first kHeadroomTrialSteps steps, encoded (never committed: the
/// trial's temporary file goes with its encoder) with `options`.
std::map<std::pair<int, Int3>, uint64_t> trialBlockBytes(
    std::vector<RangedStep>& steps, const std::vector<double>& times, const EncoderOptions& options,
    const RunOptions& run, double lo, double hi, bool missing, const std::string& path) {
  RunEncoder trial(path, options, run.keyInterval, lo, hi);
  if (missing) trial.expectMissingSamples();
  const size_t count = std::min(steps.size(), size_t(kHeadroomTrialSteps));
  for (size_t k = 0; k < count; ++k) trial.addStep(steps[k], times[k]);
  return trial.stepStats().blockBytes;
}

/// encodeRun's trial of the first step's headroom (encode_run.hpp): the blocks that got it, or
/// unset where no step can refer to another (one step, key interval 1, no headroom asked, or a
/// mode without a bound).
std::function<bool(int, Int3)> firstStepHeadroomByTrial(std::vector<RangedStep>& steps,
                                                        const std::vector<double>& times,
                                                        const EncoderOptions& options,
                                                        const RunOptions& run, double lo, double hi,
                                                        bool missing, const std::string& path,
                                                        int64_t& chosenBlocks) {
  chosenBlocks = 0;
  if (steps.size() < 2 || run.keyInterval < 2 || !(options.runCodedShare < 1) ||
      !bounded(options.mode) || !options.compact)
    return {};
  EncoderOptions with = options, without = options;  // both keep their first step's blocks
  with.firstStepHeadroom = [](int, Int3) { return true; };
  without.progress = with.progress = nullptr;
  const auto a = trialBlockBytes(steps, times, without, run, lo, hi, missing, path);
  const auto b = trialBlockBytes(steps, times, with, run, lo, hi, missing, path);
  auto chosen = std::make_shared<std::set<std::pair<int, Int3>>>();
  for (const auto& [block, bytes] : b) {
    const auto it = a.find(block);
    if (it != a.end() && bytes < it->second) chosen->insert(block);
  }
  chosenBlocks = int64_t(chosen->size());
  return [chosen](int level, Int3 block) { return chosen->count({level, block}) != 0; };
}

}  // namespace

RunStats encodeRun(const std::vector<VolumeSource*>& steps, const EncoderOptions& options,
                   const RunOptions& run, const std::string& path) {
  if (steps.empty()) throw InvalidArgument("encode: a run needs at least one step");
  std::vector<double> times = run.times;
  if (times.empty())
    for (size_t k = 0; k < steps.size(); ++k) times.push_back(double(k));
  if (times.size() != steps.size())
    throw InvalidArgument("encode: " + std::to_string(times.size()) + " time values for " +
                          std::to_string(steps.size()) + " steps");
  const StepGrid grid(*steps[0]);
  for (size_t k = 0; k < steps.size(); ++k) {  // refused before anything is read or written
    if (!std::isfinite(times[k]) || (k > 0 && !(times[k] > times[k - 1])))
      throw InvalidArgument("encode: time values must increase: step " + std::to_string(k) +
                            " has " + std::to_string(times[k]));
    const std::string d = gridDifference(grid, *steps[k]);
    if (!d.empty())
      throw InvalidArgument("encode: step " + std::to_string(k) + " (" + steps[k]->name() +
                            "): " + d);
  }
  if (run.keyInterval < 1)
    throw InvalidArgument("encode: key interval " + std::to_string(run.keyInterval) + " < 1");
  const auto t0 = std::chrono::steady_clock::now();
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  std::vector<RangedStep> ranged;  // each step's range, read once
  ranged.reserve(steps.size());
  bool anyMissing = false;
  for (VolumeSource* s : steps) {
    double a, b;
    bool missing = false;
    volumeValueRange(*s, a, b, &missing, options.threads);
    ranged.emplace_back(*s, a, b, missing);
    lo = std::min(lo, a);
    hi = std::max(hi, b);
    anyMissing = anyMissing || missing;
  }
  const double rangeSeconds = secondsSince(t0);
  int64_t headroomBlocks = 0;
  EncoderOptions runOptions = options;
  // The trial's blocks of the first step, kept for the run's (each block's outcome and payload:
  // at most the first step's stored bytes twice).
  runOptions.firstStepBlocks = std::make_shared<FirstStepBlocks>();
  runOptions.firstStepHeadroom = firstStepHeadroomByTrial(ranged, times, runOptions, run, lo, hi,
                                                          anyMissing, path, headroomBlocks);
  runOptions.firstStepBlocks->startTaking();
  const double trialSeconds = secondsSince(t0) - rangeSeconds;
  RunEncoder encoder(path, runOptions, run.keyInterval, lo, hi);
  if (anyMissing) encoder.expectMissingSamples();
  for (size_t k = 0; k < steps.size(); ++k) encoder.addStep(ranged[k], times[k]);
  RunStats stats = encoder.commit();
  stats.rangeSeconds = rangeSeconds;
  stats.trialSeconds = trialSeconds;
  stats.headroomBlocks = headroomBlocks;
  stats.firstStepTaken = runOptions.firstStepBlocks->taken();
  stats.seconds = secondsSince(t0);
  return stats;
}

RunStats appendStep(VolumeSource& step, double time, const EncoderOptions& options,
                    const std::string& path) {
  const auto t0 = std::chrono::steady_clock::now();
  std::unique_ptr<RunWriter> writer = RunWriter::append(path);
  const VolumeHeader& h = writer->header();
  std::string difference;
  if (step.dims() != h.dims)
    difference = "dims differ from the run's";
  else if (step.origin() != h.origin)
    difference = "origin differs from the run's";
  else if (step.spacing() != h.spacing)
    difference = "spacing differs from the run's";
  else if (h.sourceBytesPerSample != 0 && step.bytesPerVoxel() != h.sourceBytesPerSample)
    difference = "samples of " + std::to_string(step.bytesPerVoxel()) +
                 " bytes differ from the run's " + std::to_string(h.sourceBytesPerSample);
  if (!difference.empty())
    throw InvalidArgument("encode --append: " + step.name() + ": " + difference + " (" + path +
                          ")");
  if (std::isnan(time)) time = writer->lastTime() + 1;
  RunStats stats;
  stats.valueMin = h.valueMin;
  stats.valueMax = h.valueMax;
  stats.bound = writer->absoluteBound();
  EncoderOptions stepOptions = options;  // the run's partition, coding and bound
  stepOptions.levels = h.levels;
  stepOptions.blocksPerAxis = h.blocksPerAxis;
  stepOptions.degree = h.degree;
  stepOptions.mode = h.mode;
  stepOptions.boundKind = h.boundKind;
  stepOptions.errorBound = stats.bound;
  stepOptions.relativeBound = false;
  stepOptions.runStep = true;
  if (writer->keyInterval() == 1) stepOptions.runCodedShare = 1.0;
  WrittenStep previous(*writer);
  stepOptions.previous = &previous;
  StepSink sink(writer, path, &h, h, 0, stats.bound, time);
  stats.steps.push_back(encodeVolume(step, stepOptions, sink));
  sink.end();
  stats.references.push_back(sink.references);
  stats.residuals.push_back(sink.residuals);
  stats.decodedBefore.push_back(previous.takeDecodedCount());
  stats.bytesOut = writer->commit();
  stats.seconds = secondsSince(t0);
  return stats;
}

}  // namespace afam
