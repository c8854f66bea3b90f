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
// Modes: Adaptive searches every level-0 block and, at finer levels, only the children of complex
// blocks (NCP* > p+1); the others get NCP = p+1 without a search. InLevel searches every block.
// Fixed fits NCP = fixedNcp (0 = n) per axis. Downsampled stores the micro-block's samples with a
// one-sample ghost layer at the same stride (positions clamped to the volume), for trilinear
// rendering.
//
// Memory: the encoder never holds the volume. Per level it walks the rows of blocks along z, reads
// only the z-planes its sample positions need (one or two per sample, via VolumeSource::readSlab),
// and keeps the samples of the blocks being fitted: rows of blocks are gathered up to ~24 M samples
// (96 MB) per batch, at least one row. Measured peak RSS of `afam encode`: 174 MB at 512^3,
// 497 MB at 1024^3 (2 threads).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "afam/afam_file.hpp"
#include "afam/errors.hpp"
#include "afam/partition.hpp"

namespace afam {

enum class SearchMethod : uint8_t { Fast = 0, Exhaustive = 1 };

struct EncoderOptions {
  int levels = 4;
  int blocksPerAxis = 16;
  int degree = 2;
  double errorBound = 1e-4;
  bool relativeBound = false;  ///< bound = errorBound * (valueMax - valueMin)
  EncodingMode mode = EncodingMode::Adaptive;
  int fixedNcp = 0;            ///< Fixed mode: NCP per axis, 0 = n
  int threads = 0;             ///< 0 = hardware concurrency
  SearchMethod search = SearchMethod::Fast;
  int fastWindow = 3;          ///< Fast search: NCPs checked below the bisection result
  /// Called from the calling thread with the fraction done in [0, 1]; return false to cancel
  /// (encodeVolume then throws afam::Cancelled; nothing is written).
  std::function<bool(double fraction)> progress;
};

struct LevelStats {
  int64_t blocks = 0;          ///< micro-blocks of the level
  int64_t searched = 0;        ///< blocks that ran the in-level search
  int64_t complex = 0;         ///< blocks with NCP* > p+1
  int64_t fits = 0;            ///< fits performed at this level
  int64_t samples = 0;         ///< micro-block samples fitted (sum of n0 n1 n2)
  uint64_t payloadBytes = 0;   ///< sum of payload sizes
  uint64_t paperBytes = 0;     ///< the paper's layout for the same models
  double maxRmse = 0, maxError = 0;
  double seconds = 0;
  std::vector<int64_t> ncpHistogram;  ///< [k] = blocks with max-axis NCP == k
};

struct EncodeStats {
  std::vector<LevelStats> levels;
  int64_t fits = 0;
  int64_t blocks = 0;
  int64_t inputVoxels = 0;
  uint64_t bytesIn = 0;        ///< raw volume size as float32 (dims product * 4)
  uint64_t bytesOut = 0;       ///< file size (or header+index+payloads for a sink)
  uint64_t payloadBytes = 0;
  uint64_t paperBytes = 0;     ///< the paper's layout: sum of 1 + ((NCP+p)*3 + NCP^3)*4
  double seconds = 0;          ///< wall time of the whole encode
  double fitSeconds = 0;       ///< wall time of the fitting phases
  double cpuSeconds = 0;       ///< process CPU time (user + system) spent in the encode
  double maxRmse = 0, maxError = 0;
  double bound = 0;            ///< absolute RMSE bound used
  double valueMin = 0, valueMax = 0;
  int threads = 1;
  /// Input voxels per second per thread over the whole encode (wall clock / threads).
  double voxelsPerSecondPerThread() const {
    return seconds > 0 ? double(inputVoxels) / seconds / threads : 0;
  }
  /// Input voxels per CPU-second: the per-thread rate that other processes sharing the cores
  /// do not distort.
  double voxelsPerCpuSecond() const { return cpuSeconds > 0 ? double(inputVoxels) / cpuSeconds : 0; }
};

/// A scalar volume read by whole z-planes. Implementations: ArraySource, RawFileSource,
/// MarschnerLobbSource. readSlab is called from one thread at a time.
class VolumeSource {
 public:
  virtual ~VolumeSource() = default;
  virtual Index3 dims() const = 0;
  virtual std::array<double, 3> origin() const { return {0, 0, 0}; }
  virtual std::array<double, 3> spacing() const { return {1, 1, 1}; }
  virtual std::string name() const { return "scalars"; }
  /// dims[0] * dims[1] * zCount floats, x fastest, planes z0 .. z0+zCount-1.
  virtual void readSlab(int64_t z0, int64_t zCount, float* out) = 0;
  /// If the source knows its value range without a pass over the data, it says so here; else
  /// the encoder computes it (and checks for NaN/Inf) in one streaming pass.
  virtual bool knownRange(double& lo, double& hi) const {
    (void)lo;
    (void)hi;
    return false;
  }
  /// Bytes per voxel of the original data (for the compression ratio).
  virtual int bytesPerVoxel() const { return 4; }
};

/// Over a caller-owned float array (x fastest). The array must outlive the source.
class ArraySource : public VolumeSource {
 public:
  ArraySource(const float* data, Index3 dims, std::string name = "scalars",
              std::array<double, 3> origin = {0, 0, 0}, std::array<double, 3> spacing = {1, 1, 1});
  Index3 dims() const override { return dims_; }
  std::array<double, 3> origin() const override { return origin_; }
  std::array<double, 3> spacing() const override { return spacing_; }
  std::string name() const override { return name_; }
  void readSlab(int64_t z0, int64_t zCount, float* out) override;

 private:
  const float* data_;
  Index3 dims_;
  std::string name_;
  std::array<double, 3> origin_, spacing_;
};

enum class ScalarType : uint8_t { Float32, Float64, UInt8, UInt16, Int16 };
const char* scalarTypeName(ScalarType t);
ScalarType parseScalarType(const std::string& name);  ///< float32|float64|uint8|uint16|int16
int scalarTypeSize(ScalarType t);

/// Parses name_XxYxZ_type.raw (the convention of shared/data/volumes); false if it does not match.
bool parseRawName(const std::string& path, Index3& dims, ScalarType& type);

/// Over a raw little-endian file, converted to float32; reads only the planes asked for.
class RawFileSource : public VolumeSource {
 public:
  /// Throws IoError if the file cannot be opened, InvalidArgument if its size is not dims * type.
  RawFileSource(const std::string& path, Index3 dims, ScalarType type,
                std::array<double, 3> origin = {0, 0, 0}, std::array<double, 3> spacing = {1, 1, 1});
  ~RawFileSource() override;
  Index3 dims() const override { return dims_; }
  std::array<double, 3> origin() const override { return origin_; }
  std::array<double, 3> spacing() const override { return spacing_; }
  std::string name() const override;
  void readSlab(int64_t z0, int64_t zCount, float* out) override;
  int bytesPerVoxel() const override { return scalarTypeSize(type_); }
  ScalarType type() const { return type_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int fd_ = -1;
  Index3 dims_;
  ScalarType type_;
  std::array<double, 3> origin_, spacing_;
  std::vector<unsigned char> buffer_;
};

/// The Marschner-Lobb function sampled on dims over [-1, 1]^3, generated plane by plane.
class MarschnerLobbSource : public VolumeSource {
 public:
  explicit MarschnerLobbSource(Index3 dims) : dims_(dims) {}
  Index3 dims() const override { return dims_; }
  std::string name() const override { return "marschner_lobb"; }
  void readSlab(int64_t z0, int64_t zCount, float* out) override;

 private:
  Index3 dims_;
};

/// Receives the header first, then every model (from the calling thread of encodeVolume).
class ModelSink {
 public:
  virtual ~ModelSink() = default;
  virtual void begin(const VolumeHeader& header) = 0;
  virtual void add(const ModelEntry& entry, const float* payload) = 0;
};

/// Keeps every model in memory (for the VTK filter and for tests).
class InMemoryModels : public ModelSink {
 public:
  void begin(const VolumeHeader& h) override;
  void add(const ModelEntry& entry, const float* payload) override;
  VolumeHeader header;
  Partition partition;
  std::vector<ModelEntry> entries;            ///< ordered like the file: level, then linear index
  std::vector<std::vector<float>> payloads;   ///< same order
  std::vector<int64_t> levelStart;
  int64_t entryIndex(int level, Int3 ijk) const;
  /// Writes everything to an .afam file (atomic).
  void write(const std::string& path) const;
};

/// Encodes into a sink. Throws InvalidArgument (options), NumericError (NaN/Inf, naming the block),
/// IoError (source), Cancelled.
EncodeStats encodeVolume(VolumeSource& source, const EncoderOptions& options, ModelSink& sink);
/// Encodes into an .afam file, written atomically (nothing is left on error or cancel).
EncodeStats encodeVolume(VolumeSource& source, const EncoderOptions& options, const std::string& outPath);

/// In-level search on one block's samples, exposed for tests and benchmarks. Returns NCP* and
/// the fit at NCP* in `result`; `fits` counts the fits performed.
int searchNcp(class BlockFitter& fitter, const float* samples, Int3 n, int degree, double bound,
              SearchMethod method, int window, struct FitResult& result, int64_t& fits);

/// Extracts micro-block samples of (level, ijk) from a full in-memory volume (x fastest), with the
/// Partition's sampling rule (linear interpolation at fractional positions). ghost adds one sample
/// on each side at the same spacing, clamped to the volume (DS payload layout).
std::vector<float> extractBlock(const Partition& part, const float* volume, int level, Int3 ijk,
                                bool ghost = false);

/// Streams the micro-block samples of one z-row of blocks of a level from a source, reading only
/// the planes needed (two cached). Used by the encoder, `afam verify --against` and tests.
class BlockRowReader {
 public:
  BlockRowReader(VolumeSource& source, const Partition& partition);
  ~BlockRowReader();
  /// out[j * bx + i] = samples of block (i, j, kz), x fastest; ghost as in extractBlock.
  void readRow(int level, int kz, bool ghost, std::vector<std::vector<float>>& out);
  uint64_t bytesRead() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Samples of a decoded micro-block on its own n0 x n1 x n2 grid: the spline evaluated at the
/// sample parameters (B-spline modes) or the stored samples without the ghost layer (DS).
void decodeBlockSamples(const ModelEntry& entry, const float* payload, EncodingMode mode, std::vector<float>& out);

/// The sample grid of one decoded level: per axis the level's blocks' samples joined on their
/// shared boundary samples (dims), and where block i starts on each axis (start[a][i]).
struct LevelGrid {
  Index3 dims{};
  std::array<std::vector<int64_t>, 3> start;
};
LevelGrid levelGrid(const Partition& partition, int level);

/// Decodes level `level` of `file` inside the box [lo, hi] of its level grid (inclusive indices)
/// into `out`, x fastest, (hi - lo + 1) samples per axis. Reads only the blocks that own samples
/// of the box (a shared boundary sample belongs to the later block, as in `afam decode`).
/// `progress` (optional) gets fractions in [0, 1]. Throws InvalidArgument for a bad level or box.
void decodeLevelBox(const AfamFile& file, int level, const Index3& lo, const Index3& hi, float* out,
                    const std::function<void(double)>& progress = {});

}  // namespace afam
