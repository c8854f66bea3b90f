// SPDX-License-Identifier: BSD-3-Clause
#include "afam/encode/pipeline_run.hpp"

#include <cmath>
#include <utility>

#include "afam/base/errors.hpp"

namespace afam {

PipelineRun::PipelineRun() = default;
PipelineRun::~PipelineRun() = default;

void PipelineRun::require(bool condition, const std::string& what) const {
  if (!condition) throw InvalidArgument("encode: " + what);
}

void PipelineRun::setTimes(std::vector<double> times) {
  if (times == times_) return;
  drop();
  times_ = std::move(times);
}

size_t PipelineRun::stepToRead() const {
  if (underWay()) return nextStep_;
  return finished_ && !times_.empty() ? times_.size() - 1 : 0;
}

bool PipelineRun::readyToStart(double inputTime) {
  finished_.reset();
  return !underWay() && !times_.empty() && (std::isnan(inputTime) || inputTime == times_[0]);
}

void PipelineRun::start(const std::string& path, const EncoderOptions& options) {
  require(!times_.empty(), "a run needs the times of its steps");
  require(!underWay(), "a run is under way already");
  drop();
  encoder_ = std::make_unique<RunEncoder>(path, options, kKeyInterval);
  hasFillValue_ = options.hasMissingValue;
  if (hasFillValue_) encoder_->expectMissingSamples();
  path_ = path;
}

void PipelineRun::setProgress(std::function<bool(double)> progress) {
  progress_ = std::move(progress);
}

EncodeStats PipelineRun::addStep(VolumeSource& step, EncodeTeam& team) {
  require(underWay(), "no run is under way (start() first)");
  require(!complete(),
          "every one of the run's " + std::to_string(times_.size()) + " steps is encoded already");
  const double k = static_cast<double>(nextStep_), n = static_cast<double>(times_.size());
  encoder_->setProgress([this, k, n](double f) { return !progress_ || progress_((k + f) / n); });
  try {
    const EncodeStats stats = encoder_->addStep(step, times_[nextStep_], team);
    ++nextStep_;
    return stats;
  } catch (...) {
    drop();  // the run's temporary file goes with its encoder
    throw;
  }
}

EncodeStats PipelineRun::addStep(VolumeSource& step) {
  SoloTeam solo;
  return addStep(step, solo);
}

void PipelineRun::noteFillValue(bool found) { fillValueFound_ = fillValueFound_ || found; }

bool PipelineRun::fillValueNeverFound() const { return hasFillValue_ && !fillValueFound_; }

RunStats PipelineRun::commit(EncodeTeam& team, const RunOrigin& origin) {
  require(complete(), "the run has " + std::to_string(nextStep_) + " of its " +
                          std::to_string(times_.size()) + " steps");
  try {
    const RunStats stats = encoder_->commit(team);
    encoder_.reset();
    nextStep_ = 0;
    finished_ = origin;
    return stats;
  } catch (...) {
    drop();
    throw;
  }
}

RunStats PipelineRun::commit(const RunOrigin& origin) {
  SoloTeam solo;
  return commit(solo, origin);
}

void PipelineRun::drop() {
  encoder_.reset();
  nextStep_ = 0;
  hasFillValue_ = false;
  fillValueFound_ = false;
  finished_.reset();
}

}  // namespace afam
