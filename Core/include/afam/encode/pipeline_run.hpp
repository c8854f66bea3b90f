// SPDX-License-Identifier: BSD-3-Clause
// A run of known time steps encoded as a pipeline delivers them, one step an execution
// (ParaView's encoding filter on a time-varying input): the run starts at its first step, asks for
// the steps in order, reports progress across them, is written after the last, and stays current
// until its times or what it was encoded from change. The coding is RunEncoder's.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "afam/encode/encode_run.hpp"
#include "afam/encode/encode_team.hpp"
#include "afam/encode/encoder.hpp"
#include "afam/volume/volume_source.hpp"

namespace afam {

/// What a finished run was encoded from, as its caller identifies it (ParaView's encoding filter:
/// its settings' modification time and a checksum of its last step's input).
struct RunOrigin {
  uint64_t settings = 0;
  uint64_t input = 0;
};

/// The states: idle (nothing encoded), under way (steps 0..nextStep-1 added, the file not yet
/// written), finished (the file written, remembered with its RunOrigin). A step that fails, a
/// cancelled step and a failed commit leave the run idle and nothing at its path (RunEncoder);
/// a finished run's file is the caller's.
class PipelineRun {
 public:
  static constexpr int kKeyInterval = 16;  ///< the filter's key interval

  PipelineRun();
  ~PipelineRun();
  PipelineRun(const PipelineRun&) = delete;
  PipelineRun& operator=(const PipelineRun&) = delete;

  /// The steps' times (strictly increasing). A list other than the run's drops the run.
  void setTimes(std::vector<double> times);
  const std::vector<double>& times() const { return times_; }

  bool underWay() const { return encoder_ != nullptr; }
  /// What the finished run was encoded from; nullptr when none is finished.
  const RunOrigin* finishedFrom() const { return finished_ ? &*finished_ : nullptr; }
  /// The step the pipeline should deliver: the one a run under way encodes next; once a run is
  /// finished, the last (a new time asked of the output does not execute the input again); else
  /// the first.
  size_t stepToRead() const;

  /// Forgets the finished run, if any; true when `inputTime` is the first step's (NaN: the input
  /// does not say, taken as the first), where start() may follow. A run starts at its first
  /// step, whose range a relative bound refers to.
  bool readyToStart(double inputTime);
  /// Starts a run into `path` (nothing there before commit()). A fill value
  /// (options.hasMissingValue) is declared from the first step on.
  void start(const std::string& path, const EncoderOptions& options);
  /// The progress of the run from now on, in fractions of the whole run (step k of n at the
  /// fraction f of its encoding: (k + f) / n); returning false cancels it (Cancelled).
  void setProgress(std::function<bool(double)> progress);

  /// Encodes the next step at its time, by every process of `team` (collective).
  EncodeStats addStep(VolumeSource& step, EncodeTeam& team);
  EncodeStats addStep(VolumeSource& step);
  /// Whether the run's fill value was found at the step just added.
  void noteFillValue(bool found);
  /// The run has a fill value that no step added so far held.
  bool fillValueNeverFound() const;
  /// Every step is added: commit() may follow.
  bool complete() const { return underWay() && nextStep_ == times_.size(); }

  /// Writes the run (collective: the first process writes `path`) and remembers it as encoded
  /// from `origin`.
  RunStats commit(EncodeTeam& team, const RunOrigin& origin);
  RunStats commit(const RunOrigin& origin);
  /// The path of the run under way or finished.
  const std::string& path() const { return path_; }
  /// Abandons a run under way (nothing is left at its path) and forgets a finished one.
  void drop();

 private:
  void require(bool condition, const std::string& what) const;

  std::vector<double> times_;
  std::unique_ptr<RunEncoder> encoder_;
  std::string path_;
  size_t nextStep_ = 0;
  bool hasFillValue_ = false, fillValueFound_ = false;
  std::optional<RunOrigin> finished_;
  std::function<bool(double)> progress_;
};

}  // namespace afam
