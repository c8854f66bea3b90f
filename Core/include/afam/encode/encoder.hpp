// SPDX-License-Identifier: BSD-3-Clause
// The Adaptive-FAM encoder (paper, Algorithm 1) over a streaming volume source.
//
// Levels are encoded coarse to fine (level 0 first). Per micro-block, the in-level search finds
// NCP* = the smallest scalar NCP in [p+1, n] (n = the block's largest sample count; per axis the
// NCP is clamped by clampNcp) whose RMSE is <= the bound; if none is, NCP* = n. Two searches give
// the same NCP* (tested on every block of the corpus and Marschner-Lobb 128^3):
//   - Exhaustive: the paper's loop, every NCP from p+1 to n is fitted.
//   - Fast: fit p+1 (done if it passes) and n (if n fails too, fall back to an ascending scan);
//     bisect between them for a passing NCP whose predecessor fails, then check the `window` NCPs
//     below it (and below any smaller passing NCP found) so that a non-monotone error curve that
//     dips under the bound just below the bisection point is still found.
// A searched block whose samples are much smoother along some axes than along the roughest one
// (layers, sheets, Marschner-Lobb's slow z) then gets fewer control points on those axes
// (refineNcpPerAxis, ncp_search.hpp; EncoderOptions::perAxisNcp), the bound still met.
// Modes: Adaptive searches every level-0 block and, at finer levels, only the children of complex
// blocks (NCP* > p+1); the others get NCP = p+1 without a search. InLevel searches every block.
// Fixed fits NCP = fixedNcp (0 = n) per axis. Downsampled stores the micro-block's samples with a
// one-sample ghost layer at the same stride (positions clamped to the volume), for trilinear
// rendering.
//
// Memory: the encoder never holds the volume. Per level it walks the rows of blocks along z, reads
// only the z-planes its sample positions need (one or two per sample, via VolumeSource::readSlab),
// and keeps the samples of the blocks being fitted: rows of blocks are gathered up to ~24 M samples
// (96 MB) per batch, at least one row, and the next batch is sampled while the current one is
// fitted (two batches in memory, and up to 256 MB of planes being filtered: peak RSS 1.9 GB at
// 1024^3 with 16 threads). Measured peak RSS before that overlap of `afam encode`: 174 MB at 512^3,
// 497 MB at 1024^3 (2 threads).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/encode/encode_team.hpp"
#include "afam/encode/model_sink.hpp"
#include "afam/entropy/entropy_stage.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/format/partition.hpp"
#include "afam/sampling/block_sampling.hpp"
#include "afam/sampling/level_sampler.hpp"
#include "afam/search/least_squares_batch.hpp"
#include "afam/search/ncp_search.hpp"
#include "afam/spline/fit.hpp"
#include "afam/volume/volume_source.hpp"

namespace afam {

class FirstStepBlocks;  // first_step_blocks.hpp

/// The models of the step before, for coding a run of steps in time (encode_run.hpp): a block
/// whose model there still meets the bound on its new samples is stored as a reference to it.
/// Called from the encoder's worker threads, each block from one thread at a time.
class PreviousStep {
 public:
  virtual ~PreviousStep() = default;
  /// Whether there is a step before; then `mayRefer` says whether the block may refer to its model
  /// (false at the block's key step: the key interval), and only when it may is `entry` filled
  /// with that model's entry (the owner's payload fields). Nothing is decoded.
  virtual bool entry(int level, Int3 block, ModelEntry& entry, bool& mayRefer) const = 0;
  /// That model's decoded control points (`entry` from entry()).
  virtual void control(int level, Int3 block, const ModelEntry& entry, FitResult& model) const = 0;
  /// Runs use(values, count) on that model decoded on the block's samples (decodeBlockSamples of
  /// its control points; `entry` from entry() with the block's samples): kept from one step to the
  /// next while the block keeps the model, so that a block referring to it for many steps is
  /// decoded and evaluated once.
  virtual void values(int level, Int3 block, const ModelEntry& entry,
                      const std::function<void(const float*, size_t)>& use) const = 0;
};

/// A run's block whose model at the step before misses its new samples by more than this many
/// bounds (RMSE) is coded to the whole bound (EncoderOptions::runCodedShare).
constexpr double kDriftForHeadroom = 1.2;

struct EncoderOptions {
  int levels = 0;         ///< 0: from the volume's dimensions (defaultPartition)
  int blocksPerAxis = 0;  ///< finest blocks per axis; 0: from the dimensions (defaultPartition)
  int degree = 2;
  double errorBound = 1e-4;
  bool relativeBound = false;  ///< bound = errorBound * (valueMax - valueMin)
  /// Bounded modes: what the bound holds, each block's RMSE on its samples or every sample's
  /// error (a pointwise bound; written as format version 3, docs/FORMAT.md).
  BoundKind boundKind = BoundKind::Rmse;
  EncodingMode mode = EncodingMode::Adaptive;
  int fixedNcp = 0;  ///< Fixed mode: NCP per axis, 0 = n
  int threads = 0;   ///< 0 = hardware concurrency
  SearchMethod search = SearchMethod::Fast;
  int fastWindow = 3;  ///< Fast search: NCPs checked below the bisection result
  /// Bounded modes: store each block in its smallest form within the bound (a constant, a coded
  /// spline or coded samples; block_codec.hpp). false: float32 splines, the paper's payloads.
  bool compact = true;
  /// Searched blocks whose samples are much smoother along some axes get fewer control points
  /// there (refineNcpPerAxis); false: the paper's one NCP for all axes.
  bool perAxisNcp = true;
  /// Compact payloads: their entropy stage (entropy_stage.hpp): per payload a lanes frame unless
  /// zstd's is clearly smaller, or one of them everywhere (Lanes: every coded payload
  /// GPU-decodable).
  EntropyStage entropy = EntropyStage::Auto;
  /// Called from the calling thread with the fraction done in [0, 1]; return false to cancel
  /// (encodeVolume then throws afam::Cancelled; nothing is written).
  std::function<bool(double fraction)> progress;
  /// Bounded modes: the step before of a run (encode_run.hpp); nullptr for one volume.
  const PreviousStep* previous = nullptr;
  /// Bounded modes, a run's steps (runStep, set by the run encoder): a block that is coded (on its
  /// own or as a residual) where it moved by at most kDriftForHeadroom bounds since the step
  /// before, or at a key step, is held to this share of the bound, the rest left to the steps
  /// after, which keep its model as a reference while the data drifts by less. The first step
  /// (but for firstStepHeadroom's blocks), blocks that move faster and a run of key interval 1 (no
  /// step refers to another) are coded to the bound. 1 codes every block to the bound. In (0, 1].
  /// Measured on real and generated runs: docs/BENCHMARKS.md, "Headroom for references".
  double runCodedShare = 0.7;
  bool runStep = false;
  /// A run's first step (runStep, no step before): the blocks coded with runCodedShare's headroom,
  /// as at a later key step; unset, none. encodeRun decides them by a trial of the first steps
  /// (encode_run.hpp); a run given one step at a time cannot know, so its first step is coded to
  /// the bound.
  std::function<bool(int level, Int3 block)> firstStepHeadroom;
  /// A run's first step: its blocks kept while encodeRun's trial encodes it, taken when the run
  /// encodes it again (first_step_blocks.hpp); null: every block fitted.
  std::shared_ptr<FirstStepBlocks> firstStepBlocks;
  /// The source's samples equal to missingValue were turned into NaN before they reached the
  /// encoder (MissingValueSource): the file records the value as what marked them. NaN samples
  /// are always missing: the bound holds on the others, and a reader gives NaN back.
  bool hasMissingValue = false;
  double missingValue = 0;
  /// Bounded modes with an RMSE bound: least-squares residuals that answer the NCP searches'
  /// questions ahead, a batch of blocks at a time (ncp_verdicts.hpp): the GPU's
  /// (afam/cuda/encode/make_gpu_least_squares.hpp) or the CPU reference. The searches then fit
  /// about once a block and find the same NCPs. Null: every question is a fit. Should it throw, the
  /// encode goes on fitting (EncodeStats::aheadFailure says why).
  std::shared_ptr<LeastSquaresBatch> leastSquares;
  /// Spline modes, one process: a copy of the volume, loaded as the encode scans its range, that
  /// filters the coarse levels' blocks (level_sampler.hpp: the GPU's, or the CPU reference) in
  /// place of a read and a filtering of the volume for each. Unused where it cannot hold the
  /// volume, or the volume has missing samples (EncodeStats::levelSampler says which). The same
  /// file either way. Null: every level read and filtered on the CPU.
  std::shared_ptr<LevelSampler> levelSampler;
};

/// The value range of a volume's valid samples (one pass unless the source knows it, on `threads`
/// threads where the source allows concurrentReads; 0: all cores); NumericError naming the first
/// sample that is infinite. `missing`: whether a sample is NaN (missing).
void volumeValueRange(VolumeSource& source, double& vmin, double& vmax, bool* missing = nullptr,
                      int threads = 1);

struct LevelStats {
  int64_t blocks = 0;         ///< micro-blocks of the level
  int64_t searched = 0;       ///< blocks that ran the in-level search
  int64_t complex = 0;        ///< blocks with NCP* > p+1
  int64_t exact = 0;          ///< blocks no NCP could fit within the bound, stored as their samples
  int64_t reducedDegree = 0;  ///< blocks with an axis of 2..degree samples (degree lowered there)
  int64_t fits = 0;           ///< fits performed at this level
  int64_t samples = 0;        ///< micro-block samples fitted (sum of n0 n1 n2)
  uint64_t payloadBytes = 0;  ///< sum of stored payload sizes
  std::array<int64_t, 5>
      kinds{};  ///< blocks per BlockKind (spline, samples, constant, interpolant, empty)
  uint64_t paperBytes = 0;  ///< the paper's layout for the same models
  double maxRmse = 0, maxError = 0;
  double seconds = 0;
  double sampleSeconds =
      0;  ///< time spent sampling the volume (overlaps fitting after the first batch)
  /// Seconds the fitting threads together waited for sampled blocks (sampling slower than fitting,
  /// or a level's first batch).
  double fitWaitSeconds = 0;
  std::vector<int64_t> ncpHistogram;  ///< [k] = blocks with max-axis NCP == k
  /// EncoderOptions::leastSquares: residuals asked ahead of the searches, in how many rounds; the
  /// seconds spent asking (on a thread of its own, beside the fitting of the batches before and
  /// the sampling of the next) and of them waiting for the residuals.
  int64_t askedAhead = 0, aheadRounds = 0;
  double aheadSeconds = 0, residualSeconds = 0;
  /// Of aheadSeconds: the blocks' questions prepared on the CPU (their roughness, the noise probe),
  /// and their samples handed to the device (LeastSquaresBatch::setBlocks).
  double aheadPrepSeconds = 0, uploadSeconds = 0;
  /// The sampling thread's waits, while a batch was asked: for the batches before it to be fitted
  /// (and handed on) before it sampled the next, and for the asking to end after that.
  double drainSeconds = 0, askWaitSeconds = 0;
};

struct EncodeStats {
  std::vector<LevelStats> levels;
  int64_t fits = 0;
  int64_t askedAhead = 0;  ///< least-squares residuals asked ahead (EncoderOptions::leastSquares)
  /// Why asking ahead stopped (a GPU that failed or ran out of memory): the blocks after it were
  /// searched by fitting, the same file. Empty when it did not.
  std::string aheadFailure;
  /// EncoderOptions::levelSampler: what filtered the coarse levels ("cpu", or the GPU's name), or
  /// why it did not (empty without one); the seconds its loads took on the scan's threads.
  std::string levelSampler;
  double loadSeconds = 0;
  int64_t blocks = 0;
  int64_t inputVoxels = 0;
  uint64_t bytesIn = 0;   ///< raw volume size as float32 (dims product * 4)
  uint64_t bytesOut = 0;  ///< file size (or header+index+payloads for a sink)
  uint64_t payloadBytes = 0;
  uint64_t paperBytes = 0;  ///< the paper's layout: sum of 1 + ((NCP+p)*3 + NCP^3)*4
  double seconds = 0;       ///< wall time of the whole encode
  double scanSeconds = 0;   ///< wall time of the range scan (and the level sampler's loads)
  double fitSeconds = 0;    ///< wall time of the fitting phases
  double cpuSeconds = 0;    ///< process CPU time (user + system) spent in the encode
  double maxRmse = 0, maxError = 0;
  double bound = 0;  ///< absolute RMSE bound used
  double valueMin = 0, valueMax = 0;
  int threads = 1;
  int levelsUsed = 0, blocksPerAxisUsed = 0;  ///< the partition encoded (defaults resolved)
  /// Input voxels per second per thread over the whole encode (wall clock / threads).
  double voxelsPerSecondPerThread() const {
    return seconds > 0 ? double(inputVoxels) / seconds / threads : 0;
  }
  /// Input voxels per CPU-second: the per-thread rate that other processes sharing the cores
  /// do not distort.
  double voxelsPerCpuSecond() const {
    return cpuSeconds > 0 ? double(inputVoxels) / cpuSeconds : 0;
  }
};

/// Encodes into a sink. Throws InvalidArgument (options), NumericError (NaN/Inf, naming the block),
/// IoError (source), Cancelled.
EncodeStats encodeVolume(VolumeSource& source, const EncoderOptions& options, ModelSink& sink);
/// Encodes into an .afam file, written atomically (nothing is left on error or cancel).
EncodeStats encodeVolume(VolumeSource& source, const EncoderOptions& options,
                         const std::string& outPath);

/// The same models, fitted by the processes of a team (encode_team.hpp), every one calling this
/// with the same options and a source of the same volume (which may read other processes' memory).
/// Only the first process (rank 0) calls the sink, and its statistics count every block; the
/// others' count nothing but their levels' block totals and their own timings. An exception on any
/// process is thrown on all (another's as afam::Error naming its rank).
EncodeStats encodeVolume(VolumeSource& source, const EncoderOptions& options, ModelSink& sink,
                         EncodeTeam& team);
/// Into an .afam file that the first process writes (atomically; the others write nothing).
EncodeStats encodeVolume(VolumeSource& source, const EncoderOptions& options,
                         const std::string& outPath, EncodeTeam& team);

}  // namespace afam
