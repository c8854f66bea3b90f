// SPDX-License-Identifier: BSD-3-Clause
// A run of time steps of one grid encoded into one file (format version 3, docs/FORMAT.md), each
// step coded in time: a block whose model at the step before still meets the bound on the new
// step's samples is stored as a reference to it (no payload, nothing to read or decode again);
// every other block is encoded as for one volume and, when a coded residual on the step before's
// model meets the bound in fewer bytes, stored as that residual instead. The bound holds on every
// block of every step, measured against what a reader decodes; a relative bound is relative to the
// range of the whole run. Every keyInterval steps at the latest a block is stored on its own, so
// that a block at any step decodes from at most keyInterval payloads (one, and the residuals of up
// to keyInterval - 1 steps after it).
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "afam/encode/encoder.hpp"
#include "afam/volume/volume_source.hpp"

namespace afam {

struct RunOptions {
  std::vector<double> times;  ///< one per step, strictly increasing; empty: 0, 1, 2, ...
  int keyInterval = 16;       ///< K >= 1
};

struct RunStats {
  std::vector<EncodeStats> steps;
  std::vector<int64_t> references;  ///< per step, blocks stored as references
  std::vector<int64_t> residuals;   ///< per step, blocks stored as residuals on the step before
  /// Per step, blocks whose model at the step before was decoded and evaluated on their samples to
  /// measure them; the others' were kept from the step before (a block that keeps its model for
  /// many steps is decoded once, the step after the model was written).
  std::vector<int64_t> decodedBefore;
  double valueMin = 0, valueMax = 0;  ///< of the whole run
  double bound = 0;                   ///< absolute RMSE bound every block meets
  /// Bytes stored for each block (level, block) over the steps so far (payloads, residuals and
  /// masks; a reference stores none).
  std::map<std::pair<int, Int3>, uint64_t> blockBytes;
  uint64_t bytesOut = 0;
  double seconds = 0;          ///< the whole run (encodeRun: its range and trial included)
  double rangeSeconds = 0;     ///< encodeRun: reading every step's value range
  double trialSeconds = 0;     ///< encodeRun: the first step's headroom trial
  int64_t headroomBlocks = 0;  ///< encodeRun: the first step's blocks the trial gave headroom
  /// encodeRun: the first step's blocks taken from the trial's encodes (FirstStepBlocks), not
  /// fitted again
  int64_t firstStepTaken = 0;
};

/// Encodes `steps` (at least one; every one of the first's dims, origin and spacing) into `path`,
/// atomically. Throws InvalidArgument naming the step and what differs, or the times; otherwise
/// as encodeVolume. One step is written as a version-3 file of one step (the command line writes
/// a single volume as version 2 through encodeVolume).
///
/// The first step's headroom (EncoderOptions::firstStepHeadroom) is decided by a trial: the first
/// kHeadroomTrialSteps steps are encoded twice (nothing written), with the first step coded to
/// the bound and with headroom on every block, and a block of the run's first step gets headroom
/// where its bytes over those steps were fewer with it. Headroom pays where the next steps build
/// on the block (a finer model leaves its residuals more of the bound) and costs where they do
/// not (docs/BENCHMARKS.md, "The first step's headroom, by trial").
RunStats encodeRun(const std::vector<VolumeSource*>& steps, const EncoderOptions& options,
                   const RunOptions& run, const std::string& path);
constexpr int kHeadroomTrialSteps = 2;

/// A run encoded one step at a time, as a pipeline delivers them (ParaView's encoding filter on
/// a time-varying input): the coding of encodeRun, held to a bound fixed at the first step
/// (relative: to [valueMin, valueMax] when given, else to the first step's range, as later steps
/// are not known yet). Nothing is at `path` until commit(); destroyed before it, nothing is left.
///
/// The steps may be encoded by the processes of a team (encode_team.hpp; MPI ranks under
/// pvbatch), each passing its source of the same step: every process fits its share of the
/// step's blocks, the first writes the run, and then sends the step's models to the others, which
/// keep them in a scratch run of their own (a temporary file beside `path`, never committed, gone
/// when the encoder is) to code their blocks of the next step in time against the same models.
/// The file is byte for byte the one a single process writes.
class RunEncoder {
 public:
  RunEncoder(const std::string& path, const EncoderOptions& options, int keyInterval,
             double valueMin, double valueMax);
  /// The run's range is its first step's.
  RunEncoder(const std::string& path, const EncoderOptions& options, int keyInterval);
  ~RunEncoder();
  RunEncoder(const RunEncoder&) = delete;
  RunEncoder& operator=(const RunEncoder&) = delete;
  /// Encodes the next step at `time` (after the last one's). InvalidArgument naming the step when
  /// its grid or sample type is not the first step's, or the time does not follow.
  EncodeStats addStep(VolumeSource& step, double time);
  /// The same, by every process of `team` (collective; each with its source of the step). Only
  /// the first process's statistics count every block (encodeVolume with a team).
  EncodeStats addStep(VolumeSource& step, double time, EncodeTeam& team);
  /// Before the first step: the run has missing samples (NaN) at some step, which its header
  /// declares from the first step on (encodeRun calls it when its first pass finds one). A run
  /// without it refuses a later step with missing samples, by name.
  void expectMissingSamples();
  /// The progress callback of the steps from now on (EncoderOptions::progress: fractions of the
  /// step; returning false cancels it, Cancelled).
  void setProgress(std::function<bool(double)> progress);
  /// The statistics of the steps encoded so far (bytesOut and seconds: 0 before commit).
  const RunStats& stepStats() const;
  /// Writes the run (atomically, as encodeRun) and returns its statistics.
  RunStats commit();
  /// The same, collective: the first process writes the run, the others drop their scratch run.
  RunStats commit(EncodeTeam& team);

 private:
  struct State;
  std::unique_ptr<State> s_;
};

/// Appends `step` to the run at `path` in place (RunWriter::append: a kill at any moment leaves
/// the run with its old or its new steps), coded in time against the run's last step and held to
/// the bound the run was encoded with. `time`: NaN for the last step's time + 1. Throws
/// InvalidArgument when the step's grid is not the run's (naming what differs) or the time does
/// not follow, and as RunWriter::append for a file that is not a run.
RunStats appendStep(VolumeSource& step, double time, const EncoderOptions& options,
                    const std::string& path);

}  // namespace afam
