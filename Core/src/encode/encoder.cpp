// SPDX-License-Identifier: BSD-3-Clause
#include "afam/encode/encoder.hpp"

#include <algorithm>
#include <atomic>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>
#include <deque>
#include <future>
#include <limits>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>

#include "afam/base/any_nan.hpp"
#include "afam/base/seconds_since.hpp"
#include "afam/base/task_stream.hpp"
#include "afam/base/worker_pool.hpp"
#include "afam/search/ncp_search.hpp"
#include "afam/search/ncp_verdicts.hpp"
#include "afam/spline/fit.hpp"
#include "block_encoding.hpp"
#include "fitted_blocks.hpp"

namespace afam {

namespace {

using Clock = std::chrono::steady_clock;
double processCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

}  // namespace

// ------------------------------------------------------------------------------------------------
// Encoder, in steps: value range, header, then the levels' batches of block rows in one stream
// (sample, fit in parallel, hand to the sink in order, count).

namespace {

/// Spline modes fit coarse levels to the box-filtered volume; DS keeps the paper's strided samples.
LevelSampling levelSampling(EncodingMode mode) {
  return mode == EncodingMode::Downsampled ? LevelSampling::Point : LevelSampling::Box;
}

void validateOptions(const EncoderOptions& opt) {
  if (opt.degree < 1 || opt.degree > 5)
    throw InvalidArgument("encode: degree " + std::to_string(opt.degree) + " outside [1, 5]");
  if (!std::isfinite(opt.errorBound) || opt.errorBound < 0)
    throw InvalidArgument("encode: error bound " + std::to_string(opt.errorBound) +
                          " must be finite and > 0");
  if (bounded(opt.mode) && opt.errorBound == 0)
    throw InvalidArgument(
        "encode: error bound 0 asks for an exact copy: give a positive bound (e.g. --error-bound "
        "1e-6 --relative) or use --mode fixed --ncp 0 (interpolation at every sample)");
  if (opt.fixedNcp < 0) throw InvalidArgument("encode: --ncp must be >= 0");
  if (opt.boundKind == BoundKind::MaxError && !bounded(opt.mode))
    throw InvalidArgument(
        std::string("encode: a pointwise bound (--max-error) needs a bounded mode "
                    "(adaptive or inlevel), not ") +
        modeName(opt.mode));
  if (!(opt.runCodedShare > 0 && opt.runCodedShare <= 1))
    throw InvalidArgument("encode: the share of the bound a run's coded blocks keep (" +
                          std::to_string(opt.runCodedShare) + ") must be in (0, 1]");
}

/// The finest-level block holding sample xyz (for messages).
Int3 finestBlockOf(const Partition& part, const int64_t xyz[3]) {
  const int lf = part.levels() - 1;
  const Int3 nb = part.blocksPerAxis(lf);
  Int3 blk{0, 0, 0};
  for (int a = 0; a < 3; ++a) {
    Int3 probe{0, 0, 0};
    for (int j = 0; j < nb[a]; ++j) {
      probe[a] = j;
      if (part.extent(lf, probe).hi[a] >= xyz[a]) {
        blk[a] = j;
        break;
      }
    }
  }
  return blk;
}

/// Progress in [0, 1] over the range scan and the levels, weighted by samples.
class EncodeProgress {
 public:
  EncodeProgress(const Partition& part, const EncoderOptions& opt) : callback_(opt.progress) {
    for (int l = 0; l < part.levels(); ++l) {
      const Int3 b = part.blocksPerAxis(l);
      double s = 1;
      for (int a = 0; a < 3; ++a) {
        Int3 ijk{0, 0, 0};
        double sum = 0;
        for (int i = 0; i < b[a]; ++i) {
          ijk[a] = i;
          sum += part.extent(l, ijk).samples[a];
        }
        s *= sum;
      }
      levelWork_.push_back(s);
      total_ += s;
    }
    rangeWork_ = (opt.relativeBound ? 0.05 : 0.02) * total_;
    total_ += rangeWork_;
  }
  /// false when the caller asked to cancel.
  bool report(double extra) const {
    return !callback_ || callback_(std::min(1.0, (done_ + extra) / total_));
  }
  double rangeWork() const { return rangeWork_; }
  void finishRange() { done_ += rangeWork_; }
  void finishLevel(int l) { done_ += levelWork_[size_t(l)]; }

 private:
  std::function<bool(double)> callback_;
  std::vector<double> levelWork_;
  double total_ = 0, rangeWork_ = 0, done_ = 0;
};

Cancelled cancelled() { return Cancelled("encoding cancelled"); }

/// lo/hi extended by the n values (four lanes at a time: min/max vectorised); false if one is NaN
/// or infinite (lo/hi are then incomplete).
bool extendRange(const float* v, size_t n, float& lo, float& hi) {
  using Lanes = float __attribute__((vector_size(16)));
  using Flags = int __attribute__((vector_size(16)));
  const Lanes big = {FLT_MAX, FLT_MAX, FLT_MAX, FLT_MAX};
  Lanes l = {lo, lo, lo, lo}, h = {hi, hi, hi, hi};
  Flags bad = {0, 0, 0, 0};
  size_t i = 0;
  for (; i + 4 <= n; i += 4) {
    Lanes x;
    std::memcpy(&x, v + i, sizeof x);
    bad |= !(x <= big && x >= -big);
    l = x < l ? x : l;
    h = x > h ? x : h;
  }
  bool finite = true;
  for (int t = 0; t < 4; ++t) {
    finite = finite && bad[t] == 0;
    lo = std::min(lo, l[t]);
    hi = std::max(hi, h[t]);
  }
  for (; i < n; ++i) {
    finite = finite && std::isfinite(v[i]);
    lo = std::min(lo, v[i]);
    hi = std::max(hi, v[i]);
  }
  return finite;
}

/// NumericError naming the first infinite sample of a slab starting at plane z; none: returns
/// whether the slab has a NaN (a missing sample).
bool checkSlab(const std::vector<float>& buf, int64_t z, const VolumeSource& source,
               const Partition& part) {
  const auto inf = std::find_if(buf.begin(), buf.end(), [](float v) { return std::isinf(v); });
  if (inf == buf.end()) return true;  // extendRange saw a NaN
  const Index3 dims = source.dims();
  const int64_t plane = dims[0] * dims[1], i = int64_t(inf - buf.begin());
  const int64_t xyz[3] = {i % dims[0], (i / dims[0]) % dims[1], z + i / plane};
  std::ostringstream msg;
  msg << "encode: sample (" << xyz[0] << ", " << xyz[1] << ", " << xyz[2] << ") of "
      << source.name() << " is " << (*inf > 0 ? "+Inf" : "-Inf") << ", in "
      << Partition::blockName(part.levels() - 1, finestBlockOf(part, xyz))
      << "; the encoder needs finite values (NaN marks a missing sample)";
  throw NumericError(msg.str());
}

/// Worker threads for a requested count (0 or less: every core).
int encoderThreads(int requested) {
  return std::max(1, requested > 0 ? requested : int(std::thread::hardware_concurrency()));
}

/// One chunk of planes of the range pass: its valid samples' range, whether one is NaN, and the
/// error naming its first infinite sample (empty when none).
struct RangeChunk {
  float lo = std::numeric_limits<float>::infinity(), hi = -std::numeric_limits<float>::infinity();
  bool missing = false;
  std::string infinite;
};

/// Where the range scan loads the volume's copy (EncoderOptions::levelSampler): as the source
/// stores its samples, or as floats; the seconds the loads took, summed over the scan's threads.
/// A load that fails (a GPU out of order) stops the loads, not the scan: the coarse levels are
/// then filtered on the CPU, and `failure` says why.
struct SlabLoad {
  LevelSampler* sampler = nullptr;
  std::optional<SampleType> stored;
  std::atomic<int64_t> nanoseconds{0};
  std::atomic<bool> failed{false};
  std::mutex mutex;
  std::string failure;
  void put(int64_t z, int64_t nz, const void* samples) {
    if (failed) return;
    const auto t0 = Clock::now();
    try {
      sampler->load(z, nz, samples);
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(mutex);
      if (!failed.exchange(true)) failure = e.what();
    }
    nanoseconds += std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t0).count();
  }
};

/// The range of `count` samples stored as T (1- or 2-byte integers: every value a float exactly).
template <typename T>
void storedRange(const void* samples, size_t count, float& lo, float& hi) {
  const T* v = static_cast<const T*>(samples);
  T a = v[0], b = v[0];
  for (size_t i = 1; i < count; ++i) {
    a = std::min(a, v[i]);
    b = std::max(b, v[i]);
  }
  lo = std::min(lo, float(a));
  hi = std::max(hi, float(b));
}

/// Planes of 1- or 2-byte integers as the source stores them (`stored`): their range (a float is
/// never NaN or infinite there), handed to `load` (where given) as they are; false for other types.
bool scanStored(VolumeSource& source, SampleType stored, int64_t z, int64_t nz, SlabLoad* load,
                RangeChunk& c) {
  if (sampleTypeSize(stored) > 2) return false;
  thread_local std::vector<unsigned char> raw;
  const size_t count = size_t(nz * source.dims()[0] * source.dims()[1]);
  if (count == 0) return true;
  raw.resize(count * size_t(sampleTypeSize(stored)));
  source.readStoredRows(z, nz, 0, source.dims()[1], raw.data());
  if (load) load->put(z, nz, raw.data());
  switch (stored) {
    case SampleType::Int8:
      storedRange<int8_t>(raw.data(), count, c.lo, c.hi);
      break;
    case SampleType::UInt8:
      storedRange<uint8_t>(raw.data(), count, c.lo, c.hi);
      break;
    case SampleType::Int16:
      storedRange<int16_t>(raw.data(), count, c.lo, c.hi);
      break;
    default:
      storedRange<uint16_t>(raw.data(), count, c.lo, c.hi);
  }
  return true;
}

/// One chunk of the range scan: where the source stores 1- or 2-byte integers (and a load, if
/// any, takes them as stored) their range as stored; else its floats, handed to `load` as floats.
RangeChunk scanChunk(VolumeSource& source, const Partition& part, int64_t z, int64_t nz,
                     SlabLoad* load) {
  RangeChunk c;
  const std::optional<SampleType> stored = source.storedType();
  if (stored && (!load || load->stored) && scanStored(source, *stored, z, nz, load, c)) return c;
  thread_local std::vector<float> buf;
  const Index3 dims = source.dims();
  buf.resize(size_t(nz * dims[0] * dims[1]));
  source.readSlab(z, nz, buf.data());
  if (load) load->put(z, nz, buf.data());
  if (!extendRange(buf.data(), buf.size(), c.lo, c.hi)) try {
      c.missing = checkSlab(buf, z, source, part);
    } catch (const NumericError& e) {
      c.infinite = e.what();
    }
  return c;
}

/// Value range of the valid samples and Inf check in one streaming pass (unless the source knows
/// its range) over this process's share of the z-planes, in chunks of about a megabyte, on
/// `threads` threads where the source allows concurrentReads; the team reduces the shares to the
/// volume's range. `missing`: whether a sample of the share is NaN (missing). An infinite sample
/// stops the encode naming the first in z-order, whatever the threads. `load`: every plane read
/// is handed to it (the whole volume: one process).
void scanValueRange(VolumeSource& source, const Partition& part, const EncodeProgress& progress,
                    EncodeTeam& team, double& vmin, double& vmax, bool& missing, int threads = 1,
                    SlabLoad* load = nullptr) {
  missing = false;
  if (source.knownRange(vmin, vmax)) {
    missing = source.knownMissing();
    return;
  }
  const Index3 dims = source.dims();
  const int64_t plane = dims[0] * dims[1];
  const int64_t chunk =
      std::max<int64_t>(1, (int64_t(1) << 18) / std::max<int64_t>(plane, 1));  // ~1 MB
  const WorkShare planes = workShare(dims[2], team.rank(), team.size());
  const int64_t count = (planes.end - planes.first + chunk - 1) / chunk;
  std::vector<RangeChunk> chunks(size_t(std::max<int64_t>(count, 0)));
  std::atomic<int64_t> done{0};
  auto scan = [&](int, int64_t c) {
    const int64_t z = planes.first + c * chunk;
    chunks[size_t(c)] = scanChunk(source, part, z, std::min(chunk, planes.end - z), load);
    ++done;
  };
  bool stopped = false;
  auto report = [&] {
    stopped = !progress.report(progress.rangeWork() * double(done) / double(count));
    return !stopped;
  };
  if (threads > 1 && source.concurrentReads() && !source.readsOnCallingThread())
    WorkerPool(threads).run(count, scan, report);
  else
    for (int64_t c = 0; c < count && !stopped; ++c) {
      scan(0, c);
      if (!chunks[size_t(c)].infinite.empty()) break;  // named below, without reading on
      report();
    }
  if (stopped) throw cancelled();
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (const RangeChunk& c : chunks) {
    if (!c.infinite.empty()) throw NumericError(c.infinite);
    lo = std::min(lo, c.lo);
    hi = std::max(hi, c.hi);
    missing = missing || c.missing;
  }
  vmin = lo;
  vmax = hi;
}

/// A volume with missing samples: at least one valid sample, and a spline mode (DS draws its
/// samples trilinearly, with nothing to stand in for a missing one).
void checkMissing(bool missing, const EncoderOptions& opt, const VolumeSource& source, double vmin,
                  double vmax) {
  if (!(vmin <= vmax))
    throw InvalidArgument(
        "encode: " + source.name() + " has no valid sample (every sample is missing: NaN" +
        (opt.hasMissingValue ? ", the missing value" : "") + ", or 0 in a valid-point mask)");
  if (missing && opt.mode == EncodingMode::Downsampled)
    throw InvalidArgument("encode: " + source.name() +
                          " has missing samples (NaN), which mode ds cannot store: use a spline "
                          "mode (adaptive, inlevel or fixed)");
}

/// The header of a volume with missing samples: what marked them in the source.
void setMissing(const EncoderOptions& opt, VolumeHeader& h) {
  h.missing = opt.hasMissingValue ? MissingKind::Value : MissingKind::NaN;
  h.missingValue = opt.hasMissingValue ? opt.missingValue : 0.0;
}

VolumeHeader makeHeader(const VolumeSource& source, const EncoderOptions& opt, int levels,
                        double vmin, double vmax) {
  VolumeHeader header;
  header.dims = source.dims();
  header.origin = source.origin();
  header.spacing = source.spacing();
  header.valueMin = vmin;
  header.valueMax = vmax;
  header.scalarName = source.name();
  header.levels = levels;
  header.blocksPerAxis = opt.blocksPerAxis;
  header.degree = opt.degree;
  header.errorBound = opt.errorBound;
  header.relativeBound = opt.relativeBound;
  header.boundKind = opt.boundKind;
  header.mode = opt.mode;
  header.fixedNcp = opt.fixedNcp;
  header.sampling = levelSampling(opt.mode);
  header.sourceBytesPerSample = source.bytesPerVoxel();
  return header;
}

void countBlock(const BlockTask& t, bool ds, LevelStats& ls) {
  const ModelEntry& m = t.entry;
  ls.searched += t.search ? 1 : 0;
  ls.complex += t.complex ? 1 : 0;
  ls.exact += t.exact ? 1 : 0;
  ls.reducedDegree += t.reducedDegree ? 1 : 0;
  ls.fits += t.fits;
  ls.samples += int64_t(m.samples[0]) * m.samples[1] * m.samples[2];
  ls.payloadBytes += m.storedSize;
  ls.paperBytes += ds ? m.storedSize : paperModelBytes(m.ncp, m.degree);
  ++ls.kinds[size_t(m.kind)];
  ls.maxRmse = std::max(ls.maxRmse, t.rmse);
  ls.maxError = std::max(ls.maxError, t.maxError);
  const int k = std::max({m.ncp[0], m.ncp[1], m.ncp[2]});
  if (ls.ncpHistogram.size() <= size_t(k)) ls.ncpHistogram.resize(size_t(k) + 1, 0);
  ++ls.ncpHistogram[size_t(k)];
}

void addLevel(const LevelStats& ls, EncodeStats& stats) {
  stats.fits += ls.fits;
  stats.askedAhead += ls.askedAhead;
  stats.blocks += ls.blocks;
  stats.payloadBytes += ls.payloadBytes;
  stats.paperBytes += ls.paperBytes;
  stats.maxRmse = std::max(stats.maxRmse, ls.maxRmse);
  stats.maxError = std::max(stats.maxError, ls.maxError);
}

/// Sample buffers of fitted blocks, handed to the blocks sampled next: their pages are already
/// faulted in and nothing is freed or allocated a block (the batches' blocks are of a few sizes).
/// A buffer keeps its size (its stale samples): the sampling overwrites every sample, and a block
/// of the same size is then not filled with zeros first. Shared by the fitting threads (give) and
/// the sampling thread (take).
class SampleBuffers {
 public:
  std::vector<float> take() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (free_.empty()) return {};
    std::vector<float> v = std::move(free_.back());
    free_.pop_back();
    return v;
  }
  void give(std::vector<float>&& v) {
    std::lock_guard<std::mutex> lock(mutex_);
    free_.push_back(std::move(v));
  }

 private:
  std::mutex mutex_;
  std::vector<std::vector<float>> free_;
};

/// Where batches are asked ahead: how many batches before the one asked may still be fitted while
/// the next is sampled (2 measured no faster on the 2.25 G-voxel scan: the fitting threads are
/// then what the sampling waits for).
constexpr size_t kFittedBesideAsked = 1;

/// Encodes the levels, coarse to fine in one stream; one instance per encodeVolume call. In a team
/// of several processes each fits its workShare of every level, and finishLevels hands the models
/// to the first process, which alone calls the sink.
class LevelEncoder {
 public:
  LevelEncoder(VolumeSource& source, const EncoderOptions& opt, const Partition& part, double bound,
               int threads, EncodeProgress& progress, ModelSink& sink, EncodeTeam& team,
               LevelSampler* sampler, bool mayMiss)
      : mayMiss_(mayMiss),
        source_(source),
        opt_(opt),
        part_(part),
        bound_(bound),
        progress_(progress),
        sink_(sink),
        team_(team),
        sampler_(sampler),
        threads_(threads),
        pool_(threads),
        samplePool_(threads),
        askPool_(threads),
        planes_(source, part.dims()) {
    sampleLoop_ = [this](int64_t count, const std::function<void(int64_t)>& fn) {
      samplePool_.run(
          count, [&fn](int, int64_t b) { fn(b); }, [] { return true; });
    };
  }

  /// Lines of blocks of one level, sampled.
  struct Batch {
    int level = 0;
    bool prepared = false;  ///< prepareAhead ran
    /// The volume copy its blocks are boxes of (the finest level's, sampled where the level
    /// sampler holds the volume), for the device to take their samples from; else null.
    const LevelSampler* copy = nullptr;
    std::vector<BlockTask> tasks;
    int64_t endLine = 0;                ///< the first line not in this batch
    double seconds = 0;                 ///< spent sampling it
    std::vector<AheadBlock> questions;  ///< its searches to ask ahead (prepareAhead)
    AheadStats ahead;
    double aheadSeconds = 0;  ///< spent asking
    double prepSeconds = 0;   ///< of it, preparing the questions on the CPU
    /// While it was asked: the sampling thread's wait for the batches before it to be fitted
    /// (before sampling the next), and then for its asking to end.
    double drainSeconds = 0, askWaitSeconds = 0;
  };

  /// Every level's lines of blocks (this process's share), coarse to fine, streamed through the
  /// fitting pool as one stream of batches, in three stages that overlap: a batch is sampled (I/O
  /// and filtering, on the sampling pool) while the one before has its questions prepared (on the
  /// asking pool) and the one before that is asked ahead and then published to the fitting
  /// threads, which fit the batches before it. So reading the volume, preparing the questions and
  /// the device's answers each take their own time, not their sum, and the fitting threads are not
  /// left idle. A thread done with its blocks of a batch goes on to the next batch's (TaskStream),
  /// whatever its level. No level waits for the one above: a block's search is decided by its own
  /// samples (searches), so the threads a coarse level's few blocks leave idle fit the next
  /// level's. The models reach the sink in the file's order (level by level).
  std::vector<LevelStats> encodeLevels() {
    const int levels = part_.levels();
    std::vector<LevelStats> stats(static_cast<size_t>(levels));
    std::vector<FitContext> ctx;
    std::vector<WorkShare> lines;
    int64_t count = 0;
    for (int l = 0; l < levels; ++l) {
      stats[size_t(l)].blocks = part_.blockCount(l);
      ctx.push_back(fitContext(l));
      lines.push_back(share(l));
      count += (lines.back().end - lines.back().first) * part_.blocksPerAxis(l)[0];
    }
    TaskStream<BlockTask> stream(
        pool_, count, [&](int, BlockTask& t) { fitTask(ctx[size_t(t.entry.level)], t); });
    LevelClock clock(part_, lines, stream, stats);
    const auto take = [&](BlockTask& t) { handOn(t, clock, stats); };
    const auto tick = [&] { return progress_.report(clock.samplesDone()); };
    // The next batch to sample: its level and first line ((levels, 0): none is left).
    std::pair<int, int64_t> after =
        lines[0].empty() ? batchAfter(0, lines[0].end, lines) : std::pair{0, lines[0].first};
    std::optional<Batch> cur, next;  // prepared (to ask and publish), sampled (to prepare)
    int64_t first = 0;               // cur's first block in the stream
    std::deque<int64_t> earlier;     // the first blocks of the batches published before cur
    while (cur || next || after.first < levels) {
      // At most kFittedBesideAsked batches before cur still fitted while the next is sampled:
      // with cur, next and the one sampled, that many batches of samples and a few blocks more.
      const size_t inFlight = opt_.leastSquares ? kFittedBesideAsked : 0;
      const int64_t fitted = earlier.size() < inFlight ? 0
                             : inFlight == 0           ? first
                                                       : earlier[earlier.size() - inFlight];
      std::future<void> asking, preparing;
      if (cur)
        asking = std::async(std::launch::async, [&] {
          askAheadOf(*cur);
          stream.publish(std::move(cur->tasks));
        });
      if (next && !next->prepared)
        preparing = std::async(std::launch::async, [&] { prepareAhead(*next); });
      std::optional<Batch> sampled;
      try {
        if (after.first < levels) {
          const auto t0 = Clock::now();
          if (!stream.drain(fitted, take, tick)) throw cancelled();
          if (cur) cur->drainSeconds = secondsSince(t0);
          if (after.second == lines[size_t(after.first)].first) clock.started(after.first);
          sampled = gatherLines(after.first, after.second, lines[size_t(after.first)].end);
          after = batchAfter(after.first, sampled->endLine, lines);
          if (!asksAhead()) prepareAhead(*sampled);  // nothing to ask: no stage of its own
        }
      } catch (...) {  // the stages use the batches and the stream
        if (preparing.valid()) preparing.wait();
        if (asking.valid()) asking.wait();
        throw;
      }
      const auto t0 = Clock::now();
      if (preparing.valid()) preparing.get();
      if (asking.valid()) asking.get();
      if (cur) {
        cur->askWaitSeconds = secondsSince(t0);
        earlier.push_back(first);
        if (earlier.size() > kFittedBesideAsked) earlier.pop_front();
        first = stream.published();
        countBatch(*cur, stats[size_t(cur->level)]);
      }
      cur = std::move(next);
      next = std::move(sampled);
      if (!cur && next && next->prepared) std::swap(cur, next);
    }
    if (!stream.drain(count, take, tick)) throw cancelled();
    return stats;
  }

  /// Where the batch after one of level l that ended before line endLine starts: the rest of
  /// level l, else the next level with lines here; (levels, 0) when none is left.
  static std::pair<int, int64_t> batchAfter(int l, int64_t endLine,
                                            const std::vector<WorkShare>& lines) {
    if (endLine < lines[size_t(l)].end) return {l, endLine};
    do ++l;
    while (l < int(lines.size()) && lines[size_t(l)].empty());
    return {l, l < int(lines.size()) ? lines[size_t(l)].first : 0};
  }

  /// A batch's sampling and asking, in its level's statistics.
  static void countBatch(const Batch& b, LevelStats& ls) {
    ls.sampleSeconds += b.seconds;
    ls.askedAhead += b.ahead.requests;
    ls.aheadRounds += b.ahead.rounds;
    ls.aheadSeconds += b.aheadSeconds;
    ls.residualSeconds += b.ahead.residualSeconds;
    ls.aheadPrepSeconds += b.prepSeconds;
    ls.uploadSeconds += b.ahead.uploadSeconds;
    ls.drainSeconds += b.drainSeconds;
    ls.askWaitSeconds += b.askWaitSeconds;
  }

  /// After every process has run encodeLevels: the models of a team reach the first process's
  /// sink in the file's order (level by level, each level's lines in rank order), and its
  /// statistics.
  void finishLevels(std::vector<LevelStats>& stats) {
    if (team_.size() == 1) return;
    const std::vector<std::vector<uint8_t>> all = team_.gatherToFirst(outgoing_);
    outgoing_.clear();
    outgoing_.shrink_to_fit();
    std::vector<std::vector<BlockTask>> ranks(all.size());
    for (size_t r = 0; r < all.size(); ++r) readFittedBlocks(all[r], ranks[r]);
    for (int l = 0; l < part_.levels(); ++l)
      for (const std::vector<BlockTask>& tasks : ranks)
        for (const BlockTask& t : tasks)
          if (t.entry.level == l) {
            sink_.add(t.entry, t.stored.data());
            countBlock(t, ds(), stats[size_t(l)]);
          }
  }

 private:
  /// This process's lines of blocks of level l.
  WorkShare share(int l) const {
    const Int3 nb = part_.blocksPerAxis(l);
    return workShare(int64_t(nb[1]) * nb[2], team_.rank(), team_.size());
  }

  /// Each level's wall time, from its first batch's sampling to its last block handed on, and the
  /// fitting threads' wait for tasks while it was the last level handed on; the samples handed on.
  class LevelClock {
   public:
    LevelClock(const Partition& part, const std::vector<WorkShare>& lines,
               const TaskStream<BlockTask>& stream, std::vector<LevelStats>& stats)
        : stream_(stream), stats_(stats), start_(stats.size(), Clock::now()) {
      for (size_t l = 0; l < stats.size(); ++l)
        left_.push_back((lines[l].end - lines[l].first) * part.blocksPerAxis(int(l))[0]);
    }
    void started(int l) { start_[size_t(l)] = Clock::now(); }
    void handedOn(const BlockTask& t) {
      const size_t l = size_t(t.entry.level);
      samples_ += double(t.entry.samples[0]) * t.entry.samples[1] * t.entry.samples[2];
      if (--left_[l] > 0) return;
      stats_[l].seconds = secondsSince(start_[l]);
      const double waited = stream_.waitSeconds();
      stats_[l].fitWaitSeconds = waited - waitedBefore_;
      waitedBefore_ = waited;
    }
    double samplesDone() const { return samples_; }

   private:
    const TaskStream<BlockTask>& stream_;
    std::vector<LevelStats>& stats_;
    std::vector<Clock::time_point> start_;
    std::vector<int64_t> left_;
    double samples_ = 0, waitedBefore_ = 0;
  };

  /// Encodes one block of level ctx.level on a fitting thread (prepareAhead said whether it
  /// searches).
  void fitTask(const FitContext& ctx, BlockTask& t) {
    const BlockExtent e = part_.extent(ctx.level, t.ijk);
    t.entry.block = t.ijk;
    t.entry.samples = e.samples;
    if (ds())
      storeDownsampled(e, t);
    else
      encodeBlock(ctx, e, threadFitter(), t);
    buffers_.give(std::move(t.samples));
  }

  /// A fitted block, in file order: to the sink (a team's first process gathers the others').
  void handOn(BlockTask& t, LevelClock& clock, std::vector<LevelStats>& stats) {
    clock.handedOn(t);
    if (team_.size() > 1) {
      appendFittedBlock(t, outgoing_);
      return;
    }
    sink_.add(t.entry, t.stored.data());
    countBlock(t, ds(), stats[size_t(t.entry.level)]);
  }

  bool ds() const { return opt_.mode == EncodingMode::Downsampled; }

  /// Whether a block runs the search: every block of a bounded mode. The paper's cross-level
  /// reuse (search only under a coarser block that was complex, else fit the fewest points first)
  /// made each level wait for the one above; the search's first question, whether the fewest
  /// points miss the bound, is answered without a fit (fewestPointsFail), so a block asks it of its
  /// own samples instead: on the repository's volumes made large, the real-like scan and the
  /// noisy head, the same payloads with as many fits (within 0.2%) as with the reuse.
  bool searches() const { return !ds() && opt_.mode != EncodingMode::Fixed; }

  /// Lines of blocks of level l from `line` on (before endLine), until the batch holds ~4 M
  /// samples a fitting thread, at most ~24 M (in a team of several processes 256 K samples, 1 MB),
  /// at least one line. One process
  /// samples a z-row (or the part of one in the range) at a time; a member of a team one line at a
  /// time. Runs beside the fitting pool: it touches only planes_, samplePool_ and its own batch (no
  /// progress callback, which the calling thread owns).
  Batch gatherLines(int l, int64_t line, int64_t endLine) {
    const auto t0 = Clock::now();
    // One process samples ahead in batches of ~4 M samples a fitting thread, at most ~24 M: few
    // enough that the next batch mostly reuses the buffers of the batch before (SampleBuffers:
    // page faults cost ~9 us each on a VM, 0.7 s of a 5 s encode at one thread), enough that the
    // threads rarely wait at a batch's end. A member of a team holds its piece and ~1 MB of
    // samples at a time, plus the rows of the planes one line is filtered from (at most a quarter
    // of the line's samples: ChunkBudget): less than one z-row of blocks.
    const bool member = team_.size() > 1;
    const size_t budgetFloats =
        member ? size_t(1) << 18 : std::min(size_t(24) << 20, (size_t(4) << 20) * size_t(threads_));
    const Int3 nb = part_.blocksPerAxis(l);
    Batch batch;
    batch.level = l;
    if (part_.stride(l) == 1 && !ds()) batch.copy = sampler_;
    std::vector<BlockTask>& tasks = batch.tasks;
    size_t floats = 0;
    while (line < endLine && (tasks.empty() || floats < budgetFloats)) {
      const int kz = int(line / nb[1]), j0 = int(line % nb[1]);
      const int j1 = member ? j0 + 1 : int(std::min<int64_t>(nb[1], j0 + (endLine - line)));
      std::vector<Int3> row;
      for (int j = j0; j < j1; ++j)
        for (int i = 0; i < nb[0]; ++i) row.push_back({i, j, kz});
      const size_t first = tasks.size();
      tasks.resize(first + row.size());
      std::vector<std::vector<float>*> outs(row.size());
      for (size_t r = 0; r < row.size(); ++r) {
        tasks[first + r].ijk = row[r];
        tasks[first + r].entry.level = l;  // the stream's tasks say their level
        tasks[first + r].samples = buffers_.take();
        outs[r] = &tasks[first + r].samples;
      }
      if (!sampleFromCopy(l, row, outs))
        sampleBlockRow(part_, planes_, l, row, ds(), levelSampling(opt_.mode), outs, sampleLoop_,
                       member ? ChunkBudget::QuarterOfSamples : ChunkBudget::Large);
      for (size_t r = 0; r < row.size(); ++r) floats += tasks[first + r].samples.size();
      line += j1 - j0;
    }
    batch.endLine = line;
    batch.seconds = secondsSince(t0);
    return batch;
  }

  /// A coarse level's row filtered by the level sampler, where one holds the volume; false where
  /// none does, or it failed (this row and the rest then read and filtered on the CPU).
  bool sampleFromCopy(int l, const std::vector<Int3>& row, std::vector<std::vector<float>*>& outs) {
    if (!sampler_ || part_.stride(l) == 1) return false;
    try {
      sampler_->sampleRow(part_, l, row, ds(), levelSampling(opt_.mode), outs, sampleLoop_);
      return true;
    } catch (const std::exception& e) {
      samplerFailure_ = e.what();
      sampler_ = nullptr;  // its copy stays until the encode ends: batches before may read it
      return false;
    }
  }

 public:
  /// Why the level sampler stopped part way (the rows after it read on the CPU); empty if not.
  const std::string& samplerFailure() const { return samplerFailure_; }

 private:
  /// The blocks of level l's context.
  FitContext fitContext(int l) const {
    const std::optional<SampleType> stored = source_.storedType();
    const bool bytes = stored && (*stored == SampleType::UInt8 || *stored == SampleType::Int8);
    return FitContext{opt_,     bound_,
                      l,        source_.name(),
                      mayMiss_, bytes && !mayMiss_ && part_.stride(l) == 1 && !ds()};
  }

  /// Whether a batch's searches are asked ahead (EncoderOptions::leastSquares): under an RMSE
  /// bound, not in a run's steps (their bounds depend on the step before), and not after a failure.
  bool asksAhead() const {
    return opt_.leastSquares && bounded(opt_.mode) && opt_.boundKind == BoundKind::Rmse &&
           !opt_.runStep && !aheadFailed_;
  }

  /// Which of the batch's blocks search, and where asked ahead, their questions (the blocks with
  /// finite samples, their roughness and noise probe): on the asking pool, beside the device's
  /// answers to the batch before and the sampling of the next.
  void prepareAhead(Batch& b) {
    const int l = b.level;
    b.prepared = true;
    for (BlockTask& t : b.tasks) t.search = searches();
    if (!asksAhead()) return;
    const auto t0 = Clock::now();
    const FitContext ctx = fitContext(l);
    std::vector<std::optional<AheadBlock>> asked(b.tasks.size());
    askPool_.run(
        int64_t(b.tasks.size()),
        [&](int, int64_t i) {
          BlockTask& t = b.tasks[size_t(i)];
          t.verdicts = NcpVerdicts{};
          if (!t.search || (mayMiss_ && anyNaN(t.samples.data(), t.samples.size()))) return;
          const BlockExtent e = part_.extent(l, t.ijk);
          AheadBlock a;
          a.samples = t.samples.data();  // the tasks' storage stays put until they are published
          a.n = e.samples;
          a.out = &t.verdicts;
          if (b.copy) a.origin = e.lo;
          t.roughness = axisRoughness(t.samples.data(), e.samples, ctx.smallIntegers);
          a.rough = t.roughness;
          if (opt_.compact) a.probe = noiseProbeNcp(ctx, e, t, *a.rough);
          asked[size_t(i)] = a;
        },
        [] { return true; });
    for (std::optional<AheadBlock>& a : asked)
      if (a) b.questions.push_back(*a);
    b.prepSeconds = secondsSince(t0);
  }

  /// The batch's prepared questions asked of the device, their verdicts in the tasks.
  void askAheadOf(Batch& b) {
    if (b.questions.empty() || !asksAhead()) return;
    const auto t0 = Clock::now();
    const SearchSettings settings{opt_.degree, searchBound(opt_, bound_), opt_.search,
                                  opt_.fastWindow, opt_.perAxisNcp};
    try {
      b.ahead = askAhead(*opt_.leastSquares, b.questions, settings, 0, b.copy);
    } catch (const std::exception& e) {  // asking ahead only spares fits: the rest is fitted
      std::lock_guard<std::mutex> lock(aheadMutex_);
      aheadFailure_ = e.what();
      aheadFailed_ = true;
    }
    b.aheadSeconds = b.prepSeconds + secondsSince(t0);
  }

 public:
  /// Why asking ahead stopped (every block after it searched by fitting); empty when it did not.
  std::string aheadFailure() {
    std::lock_guard<std::mutex> lock(aheadMutex_);
    return aheadFailure_;
  }

 private:
  bool mayMiss_;  ///< whether a sample may be missing (the range scan found a NaN)
  VolumeSource& source_;
  const EncoderOptions& opt_;
  const Partition& part_;
  double bound_;
  EncodeProgress& progress_;
  ModelSink& sink_;
  EncodeTeam& team_;
  LevelSampler* sampler_;  ///< filters the coarse levels (null: sampleBlockRow)
  std::string samplerFailure_;
  std::vector<uint8_t> outgoing_;  ///< a team's records of its fitted blocks, every level's
  int threads_;                    ///< fitting threads (each fits with its threadFitter())
  std::atomic<bool> aheadFailed_{false};
  std::mutex aheadMutex_;
  std::string aheadFailure_;
  WorkerPool pool_;
  WorkerPool samplePool_;  ///< filters the blocks of a row in parallel, beside the fitting pool
  WorkerPool askPool_;     ///< prepares a batch's questions, beside the sampling of the next
  BlockLoop sampleLoop_;
  PlaneReader planes_;
  SampleBuffers buffers_;
};

}  // namespace

void volumeValueRange(VolumeSource& source, double& vmin, double& vmax, bool* missing,
                      int threads) {
  const Partition part(source.dims(), 1, 1);
  EncoderOptions opt;
  const EncodeProgress progress(part, opt);
  SoloTeam solo;
  bool found = false;
  scanValueRange(source, part, progress, solo, vmin, vmax, found, encoderThreads(threads));
  if (missing) *missing = found;
}

namespace {
/// Blocks per axis are one number for the three axes, each axis taking as many as its samples
/// hold (n - 1, at least 1: an anisotropic volume keeps fewer along its short axis); a request
/// that no axis can hold is a mistake, refused before any fitting, naming the longest axis.
void refuseBlocksNoAxisHolds(const Index3& dims, int blocksPerAxis) {
  int longest = 0;
  for (int a = 1; a < 3; ++a)
    if (dims[a] > dims[longest]) longest = a;
  const int64_t most = std::max<int64_t>(1, dims[longest] - 1);
  if (blocksPerAxis > most)
    throw InvalidArgument("encode: " + std::to_string(blocksPerAxis) +
                          " blocks per axis: the longest axis, " + "xyz"[longest] + ", has " +
                          std::to_string(dims[longest]) + " samples, which hold at most " +
                          std::to_string(most) + " blocks");
}
}  // namespace

namespace {
/// The level sampler this encode loads and uses, reserved for the volume as `type`
/// (stats.levelSampler says which, or why not), or null: spline modes with a level coarser than the
/// volume, one process (a team's process scans only its share of the planes), a volume whose range
/// is scanned (a run's steps, whose range the run found before, are not read again to load it: the
/// Gray-Scott run of docs/BENCHMARKS.md took 26.0 s with their loads, 23.3 s without).
LevelSampler* reserveLevelSampler(const EncoderOptions& opt, const VolumeSource& source,
                                  const Partition& part, const EncodeTeam& team, EncodeStats& stats,
                                  SampleType& type) {
  LevelSampler* sampler = opt.levelSampler.get();
  if (!sampler || team.size() > 1 || levelSampling(opt.mode) != LevelSampling::Box ||
      part.levels() < 2)
    return nullptr;
  double lo = 0, hi = 0;
  if (source.knownRange(lo, hi)) {
    stats.levelSampler = "not used: the range is known, and the volume is not scanned";
    return nullptr;
  }
  const std::optional<SampleType> stored = source.storedType();
  type = stored && levelSamplerHolds(*stored) ? *stored : SampleType::Float32;
  std::string why;
  if (!sampler->reserve(source.dims(), type, why)) {
    stats.levelSampler = "not used: " + why;
    return nullptr;
  }
  stats.levelSampler = sampler->description();
  return sampler;
}
}  // namespace

EncodeStats encodeVolume(VolumeSource& source, const EncoderOptions& opt, ModelSink& sink) {
  SoloTeam solo;
  return encodeVolume(source, opt, sink, solo);
}

EncodeStats encodeVolume(VolumeSource& source, const EncoderOptions& opt, ModelSink& sink,
                         EncodeTeam& team) {
  const auto t0 = Clock::now();
  const double cpu0 = processCpuSeconds();
  validateOptions(opt);
  const Index3 dims = source.dims();
  if (opt.levels < 0 || opt.blocksPerAxis < 0)
    throw InvalidArgument("encode: levels and blocks per axis must be >= 1 (or 0 for the default)");
  refuseBlocksNoAxisHolds(dims, opt.blocksPerAxis);
  const PartitionShape shape = defaultPartition(dims);
  EncoderOptions resolved = opt;
  if (resolved.levels == 0) resolved.levels = shape.levels;
  if (resolved.blocksPerAxis == 0) resolved.blocksPerAxis = shape.blocksPerAxis;
  const Partition part(dims, resolved.levels,
                       resolved.blocksPerAxis);  // validates levels, blocks, dims
  const int threads = encoderThreads(opt.threads);

  EncodeStats stats;
  stats.threads = threads;
  stats.inputVoxels = dims[0] * dims[1] * dims[2];
  stats.bytesIn = uint64_t(stats.inputVoxels) * uint64_t(source.bytesPerVoxel());

  EncodeProgress progress(part, opt);
  bool missing = false;
  SlabLoad load;
  SampleType loadType = SampleType::Float32;  // as the copy holds the samples
  load.sampler = reserveLevelSampler(opt, source, part, team, stats, loadType);
  const struct Release {  // the volume's copy, however the encode ends
    LevelSampler* sampler;
    ~Release() {
      if (sampler) sampler->release();
    }
  } release{load.sampler};
  if (load.sampler && loadType != SampleType::Float32) load.stored = loadType;
  teamStep(team, [&] {
    scanValueRange(source, part, progress, team, stats.valueMin, stats.valueMax, missing, threads,
                   load.sampler ? &load : nullptr);
  });
  stats.scanSeconds = secondsSince(t0);
  stats.loadSeconds = 1e-9 * double(load.nanoseconds.load());
  if (load.sampler && (missing || load.failed)) {  // its filter has no rule for missing samples
    load.sampler->release();
    load.sampler = nullptr;
    stats.levelSampler =
        "not used: " + (load.failed ? load.failure : std::string("the volume has missing samples"));
  }
  team.reduceRange(stats.valueMin, stats.valueMax);
  std::vector<uint8_t> anyMissing{uint8_t(missing ? 1 : 0)};
  team.mergeFlags(anyMissing);
  checkMissing(anyMissing[0] != 0, opt, source, stats.valueMin, stats.valueMax);
  progress.finishRange();
  stats.bound =
      opt.relativeBound ? opt.errorBound * (stats.valueMax - stats.valueMin) : opt.errorBound;
  teamStep(team, [&] {  // the first process alone hands models to the sink
    if (team.rank() == 0) {
      VolumeHeader header =
          makeHeader(source, resolved, part.levels(), stats.valueMin, stats.valueMax);
      if (anyMissing[0] != 0) setMissing(opt, header);
      sink.begin(header);
    }
  });
  stats.levelsUsed = resolved.levels;
  stats.blocksPerAxisUsed = resolved.blocksPerAxis;

  const auto tFit0 = Clock::now();
  LevelEncoder levels(source, opt, part, stats.bound, threads, progress, sink, team, load.sampler,
                      anyMissing[0] != 0);
  teamStep(team, [&] { stats.levels = levels.encodeLevels(); });
  teamStep(team, [&] { levels.finishLevels(stats.levels); });
  for (int l = 0; l < part.levels(); ++l) {
    progress.finishLevel(l);
    addLevel(stats.levels[size_t(l)], stats);
  }
  stats.fitSeconds = secondsSince(tFit0);
  stats.aheadFailure = levels.aheadFailure();
  if (!levels.samplerFailure().empty())
    stats.levelSampler += "; failed, the rest filtered on the CPU: " + levels.samplerFailure();
  stats.bytesOut = fileBytes(uint64_t(stats.blocks), stats.payloadBytes);
  stats.seconds = secondsSince(t0);
  stats.cpuSeconds = processCpuSeconds() - cpu0;
  progress.report(0);
  return stats;
}

EncodeStats encodeVolume(VolumeSource& source, const EncoderOptions& options,
                         const std::string& outPath) {
  SoloTeam solo;
  return encodeVolume(source, options, outPath, solo);
}

EncodeStats encodeVolume(VolumeSource& source, const EncoderOptions& options,
                         const std::string& outPath, EncodeTeam& team) {
  FileModelSink sink(outPath);
  const auto t0 = Clock::now();
  const double cpu0 = processCpuSeconds();
  EncodeStats stats = encodeVolume(source, options, sink, team);
  teamStep(team, [&] {
    if (team.rank() == 0) stats.bytesOut = sink.commit();
  });
  stats.seconds = secondsSince(t0);
  stats.cpuSeconds = processCpuSeconds() - cpu0;
  return stats;
}

}  // namespace afam
