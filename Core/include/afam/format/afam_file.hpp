// SPDX-License-Identifier: BSD-3-Clause
// The .afam container: one file holding every micro-model of every level of one volume.
//
// Layout (byte-exact description in docs/FORMAT.md), little-endian, offsets not pointers:
//   [0, 1024)                   FileHeader (fixed size, CRC32 over its bytes)
//   [1024, 1024 + 40 E)         index: E = one 40-byte entry per micro-block of every level,
//   ordered
//                               by level (0 = coarsest) then by the block's linear index (x
//                               fastest); CRC32 of the whole index stored in the header
//   [payloadOffset, fileSize)   payloads (payloadOffset a multiple of 64; each payload offset a
//                               multiple of 4, the float32 alignment), each with its CRC32 in its
//                               index entry
// Because the index is complete and ordered, entryIndex(level, ijk) is O(1) arithmetic, and level,
// block, samples and degree of an entry are implied (not stored).
//
// Opening reads and validates the header and the index only (every count and offset is checked
// against the file size before anything is allocated); a payload is one pread.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "afam/format/compact_form.hpp"
#include "afam/format/file_identity.hpp"
#include "afam/format/partition.hpp"

namespace afam {

enum class EncodingMode : uint8_t { Adaptive = 0, InLevel = 1, Fixed = 2, Downsampled = 3 };

/// What a file's bound promises (version 3's boundKind): the RMSE of each block's samples, or the
/// absolute error of every sample (a pointwise bound, as SZ's absolute mode and ZFP's fixed
/// accuracy promise). A file that keeps a pointwise bound is written as version 3.
enum class BoundKind : uint8_t { Rmse = 0, MaxError = 1 };
/// What marks a missing sample in a file's source (version 3's missingKind): none are missing, NaN,
/// or the fill value VolumeHeader::missingValue. A file with missing samples is version 3; its
/// readers return NaN at every missing sample whatever marked it.
enum class MissingKind : uint8_t { None = 0, NaN = 1, Value = 2 };
/// "rmse" or "max_error" (`afam info`, the reader's field data).
const char* boundKindName(BoundKind kind);
/// "none", "nan" or "value" (the reader's field data).
const char* missingKindName(MissingKind kind);

/// Name used on the command line and in `afam info`: adaptive, inlevel, fixed, ds.
const char* modeName(EncodingMode mode);
/// Parses adaptive|inlevel|fixed|ds; throws InvalidArgument otherwise.
EncodingMode parseMode(const std::string& name);

struct VolumeHeader {
  Index3 dims{1, 1, 1};
  std::array<double, 3> origin{0, 0, 0}, spacing{1, 1, 1};
  double valueMin = 0, valueMax = 0;
  std::string scalarName;  ///< at most 63 bytes are stored
  int levels = 1;
  int blocksPerAxis = 1;  ///< requested finest B (Partition reduces it on short axes)
  int degree = 2;
  double errorBound = 0;  ///< as given by the user (absolute, or relative when relativeBound)
  bool relativeBound = false;
  BoundKind boundKind = BoundKind::Rmse;  ///< what errorBound bounds
  EncodingMode mode = EncodingMode::Adaptive;
  int fixedNcp = 0;  ///< Fixed mode: requested NCP (0 = n)
  /// How coarse levels were sampled (and what their error is measured against).
  LevelSampling sampling = LevelSampling::Point;
  int sourceBytesPerSample = 0;  ///< of the encoded input (1 for uint8, ...); 0 when unknown
  MissingKind missing = MissingKind::None;
  double missingValue = 0;  ///< with MissingKind::Value: the source's fill value
};

/// The bound a header's file keeps, in the data's units: errorBound, times the value range when
/// relativeBound.
double absoluteBound(const VolumeHeader& h);

/// How a micro-model is stored (format version 2; version-1 files hold float32 splines only).
///   Spline:   B-spline of the header's degree (lowered per axis by short axes), NCP per axis.
///   Samples:  the block's samples as a degree-1 spline with NCP = samples (the implied knots put
///             each control point on its sample: trilinear interpolation, exact at the samples).
///   Constant: one value; decoded to a spline of the header's degree with p+1 equal control points.
///   Interpolant: the block's samples (always coded), decoded to the spline of the header's degree
///             with NCP = samples that interpolates them: smooth value and gradient like a fitted
///             spline, exact at the (quantized) samples.
/// Spline and Samples payloads are float32 control points, or `coded` (block_codec.hpp).
///   Empty:    (version 3, a file with missing samples) no valid sample in the block: no payload
///             (size and storedSize 0), drawn as nothing, decoded to NaN.
enum class BlockKind : uint8_t {
  Spline = 0,
  Samples = 1,
  Constant = 2,
  Interpolant = 3,
  Empty = 4
};
const char* blockKindName(BlockKind kind);

/// One stored payload of a model decoded from several (a residual chain in time, version 3).
struct PayloadPart {
  uint64_t offset = 0, storedSize = 0;
  uint32_t checksum = 0;
  bool coded = false, integerCoded = false;
  int64_t step = 0;            ///< the step whose payloads hold it
  bool lanesCoded = false;     ///< its frame is a lanes frame (entry flag bit 13)
  bool roundedPoints = false;  ///< an interpolant with rounded points (entry flag bit 14)
};

struct ModelEntry {
  int level = 0;
  Int3 block{};
  Int3 ncp{};      ///< control points per axis (DS: samples + 2)
  Int3 degree{};   ///< effective degree per axis (DS: 1)
  Int3 samples{};  ///< micro-block samples per axis (Partition::extent)
  uint64_t offset = 0;
  uint64_t size = 0;  ///< bytes of the decoded float32 control points (what readPayload gives)
  float minValue = 0, maxValue = 0, rmse = 0, maxError = 0;
  uint32_t checksum = 0;  ///< CRC32 of the stored bytes
  BlockKind kind = BlockKind::Spline;
  bool coded = false;         ///< quantized, predicted and zstd-coded (block_codec.hpp)
  bool integerCoded = false;  ///< coded with an integer form (index flag bit 9; set by the writer)
  bool lanesCoded = false;    ///< its frame is a lanes frame (index flag bit 13; set by the writer)
  /// An interpolant whose fitted control points are rounded to a step (index flag bit 14): its
  /// payload ends with the step's shift (rounded_points.hpp). Never a residual.
  bool roundedPoints = false;
  uint64_t storedSize =
      0;  ///< bytes on disk (= size for uncoded splines and samples, 4 for constants)
  /// Version 3 (a run of steps): the model is the same block's model of an earlier step,
  /// unchanged (a reference); ownerStep is the step whose payload holds it (the entry's own step
  /// when it is not a reference). offset, sizes, kind, NCP and checksum are the owner's; minValue
  /// to maxError are measured on this step's samples.
  bool reference = false;
  int64_t ownerStep = 0;
  /// Version 3: a residual (in-time coding 2): the model is the step before's decoded model plus
  /// the decoded payload (a coded difference of the same kind and NCP); offset, storedSize and
  /// checksum are the newest residual's, and AfamFile::chain() lists every payload it decodes
  /// from (chainLength of them), the independent one first.
  bool residual = false;
  uint32_t chainLength = 1;
  /// Version 3 (missing samples): some of the block's samples are missing. The stored payload
  /// starts with the coded mask; `size` counts the control points and the mask words after them
  /// (block_mask.hpp says how they lie in memory). Masked models are always independent.
  bool masked = false;
};

/// Control points of an entry's decoded model (the floats before a masked model's mask words).
inline int64_t controlCount(const ModelEntry& e) {
  return e.kind == BlockKind::Empty ? 0 : int64_t(e.ncp[0]) * e.ncp[1] * e.ncp[2];
}

/// The identity of a decoded model in its file, across every step of a run: the offset of its
/// (newest) payload. Steps that share a model (a reference) give it the same key, and no two
/// different models of one file share one (payloads never overlap and are never moved, by
/// appends either), so caches keyed by it serve every step of a run.
inline uint64_t modelKey(const ModelEntry& e) { return e.offset; }

/// Whether an entry's stored bytes are its decoded model (uncoded float32, no mask section): the
/// flags decide, never the sizes alone (a coded payload may be as long as its floats).
inline bool storedAsDecoded(const ModelEntry& e) {
  return !e.coded && !e.masked && e.kind != BlockKind::Empty && e.storedSize == e.size;
}

/// The decoded control points of a stored payload (entry.storedSize bytes) into out
/// (entry.size bytes). Throws FormatError naming `where` if the bytes do not decode.
void decodeStoredPayload(const ModelEntry& entry, const uint8_t* stored, float* out,
                         const std::string& where);

/// An interpolant's points (entry.size bytes into out) from its samples as decoded, before any
/// rounding: the spline of the entry's degree through them, as decodeStoredPayload fits it. An
/// encoder that holds a candidate's decoded samples (its quantization's reconstruction, which
/// decodeValues reproduces bit for bit) takes its points here without decoding its bytes.
void interpolantPoints(const ModelEntry& entry, const float* samples, float* out,
                       const std::string& where);
// For B-spline modes the payload is ncp.x*ncp.y*ncp.z float32 control points, x fastest.
// For Downsampled (DS) the payload is (samples+2) per axis float32 raw samples with a one-voxel
// ghost layer (clamped at the volume edge), x fastest, and ncp holds samples+2, degree holds 1.

/// CRC-32 (IEEE 802.3, the zlib polynomial), continuing from `crc` (0 to start).
uint32_t crc32(const void* data, size_t bytes, uint32_t crc = 0);

/// Payload bytes of a model: ncp product * 4.
uint64_t payloadBytes(const Int3& ncp);

/// Bytes of an entry's decoded model (ModelEntry::size): its control points, and a masked
/// model's mask words after them; 0 for an empty block.
uint64_t decodedBytes(const ModelEntry& e);

/// Bytes of a file holding `entries` models whose payloads total `payloadBytes` (header + index +
/// payloads, before the payload area's alignment padding).
uint64_t fileBytes(uint64_t entries, uint64_t payloadBytes);

/// Size in bytes the paper's layout gives the same model: 1 + ((NCP + p) * 3 + NCP^3) * 4, with
/// per-axis NCP and degree: 1 + (sum_a (ncp_a + p_a) + prod_a ncp_a) * 4.
uint64_t paperModelBytes(const Int3& ncp, const Int3& degree);

/// True when the file's first 8 bytes are the .afam magic; false when they are not or the file
/// cannot be read. Readers claim such files and let AfamFile::open say what is wrong with them.
bool startsWithAfamMagic(const std::string& path);

class AfamFile;
namespace layout {
struct FileHeader;
void openRunStep(AfamFile& file, const FileHeader& header, int64_t step);
}  // namespace layout

class AfamFile {  // read-only; opening reads only header and index (of one step)
 public:
  /// Throws FormatError (not an .afam file, damaged) or IoError (cannot open/read), each message
  /// naming the path and the problem. `step`: which time step's models entries() holds (a file
  /// of version 1 or 2 has one step); InvalidArgument when the file has no such step.
  static std::shared_ptr<const AfamFile> open(const std::string& path, int64_t step = 0);
  ~AfamFile();
  AfamFile(const AfamFile&) = delete;
  AfamFile& operator=(const AfamFile&) = delete;

  const std::string& path() const { return path_; }
  const VolumeHeader& header() const { return header_; }
  const Partition& partition() const { return partition_; }
  const std::vector<ModelEntry>& entries() const { return entries_; }
  uint32_t version() const { return version_; }
  /// Time steps of the file (1 before version 3), the one opened, and their time values.
  int64_t stepCount() const { return static_cast<int64_t>(stepTimes_.size()); }
  int64_t step() const { return step_; }
  const std::vector<double>& stepTimes() const { return stepTimes_; }
  /// Version 3: a block's model stays independent at least every keyInterval() steps.
  int keyInterval() const { return keyInterval_; }
  /// The payloads a residual entry decodes from, the independent one first (entries() says which
  /// are residuals); empty for an entry of one payload.
  const std::vector<PayloadPart>& chain(int64_t entry) const;
  /// Index of the entry of block ijk at a level; -1 if the level or block is out of range.
  int64_t entryIndex(int level, Int3 ijk) const;
  /// First entry of a level (entries of a level are contiguous, x fastest).
  int64_t levelStart(int level) const { return levelStart_.at(static_cast<size_t>(level)); }
  /// One pread of entry.size bytes into out, CRC verified (FormatError names file, level, block).
  /// Thread-safe. Throws FileChangedError instead when the open file's size or modification time
  /// is no longer what it was at open (another process truncated or rewrote it): its bytes may
  /// then belong to another file, and are neither returned nor taken for damage.
  void readPayload(int64_t entry, void* out) const;
  /// A residual entry's model from `previous`, the model of its chain without the newest payload
  /// (the model of chain(entry)[size - 2].offset, as readPayload gave it): only the newest
  /// residual is read and decoded, and the result is the floats readPayload gives. Other
  /// entries, or previous null: readPayload.
  void readPayloadOnto(int64_t entry, const float* previous, void* out) const;
  /// Reads and returns the payload as floats.
  std::vector<float> readPayload(int64_t entry) const;
  /// The entry's model as a cache keeps it: in its compact form (block_codec.hpp's CompactForm:
  /// a table of values and a 1- or 2-byte code a control point) when it is one integer-coded
  /// payload of a spline or samples model or an interpolant with rounded points, unmasked, and
  /// that form takes at most maxShare of the floats' bytes; else the floats readPayload gives
  /// (width 0). out is resized to what it holds. Throws as readPayload does.
  CompactForm readCompact(int64_t entry, double maxShare, std::vector<float>& out) const;
  /// The entry's payload as stored (entry.storedSize bytes), CRC verified, not decoded: for a
  /// decoder elsewhere (a GPU's). Throws as readPayload does; InvalidArgument for an entry that
  /// is not one payload (a residual's chain, an empty block).
  std::vector<uint8_t> readStored(int64_t entry) const;
  /// Throws FileChangedError (naming the path and what changed) when the file is no longer the
  /// one opened: rewritten or truncated in place, replaced by another file (rename) or removed.
  /// One fstat and one stat; renderers call it once per frame, before reading.
  void checkUnchanged() const;
  int nativeHandle() const { return fd_; }  ///< POSIX fd, for posix_fadvise in benchmarks
  /// The file's device, inode, size and time when opened (steps of one run on disk share device
  /// and inode; an append changes only size and time).
  const FileIdentity& identity() const { return identity_; }
  uint64_t fileSize() const { return fileSize_; }
  uint64_t payloadOffset() const { return payloadOffset_; }

 private:
  AfamFile() = default;
  void readVerifiedPayload(int64_t entry, const float* previous,
                           void* out) const;           ///< readPayloadOnto without the change check
  void throwIfChanged(const FileIdentity& now) const;  ///< FileChangedError unless now == identity_
  /// Runs `read`, then checks the descriptor whatever its outcome (bytes read while or after
  /// another process rewrote the file are neither returned nor taken for damage).
  template <typename Read>
  void readUnlessChanged(Read&& read) const;
  const ModelEntry& entryAt(int64_t entry) const;  ///< InvalidArgument when out of range
  /// One pread of `bytes` stored bytes of e into out, CRC verified (FormatError naming the block).
  void readChecked(const ModelEntry& e, void* out, size_t bytes) const;
  /// readCompact of an unmasked interpolant with rounded points (one payload).
  CompactForm readRoundedCompact(const ModelEntry& e, double maxShare,
                                 std::vector<float>& out) const;
  std::string path_;
  int fd_ = -1;
  uint32_t version_ = 0;
  uint64_t fileSize_ = 0, payloadOffset_ = 0;
  FileIdentity identity_;  ///< at open
  VolumeHeader header_;
  Partition partition_;
  std::vector<ModelEntry> entries_;
  std::vector<int64_t> levelStart_;
  std::vector<double> stepTimes_{0.0};
  std::unordered_map<int64_t, std::vector<PayloadPart>> chains_;  ///< of residual entries
  int64_t step_ = 0;
  int keyInterval_ = 1;
  friend void layout::openRunStep(AfamFile& file, const layout::FileHeader& header, int64_t step);
};

/// Writes header + index + payloads to PATH.tmp-XXXXXX, then fsync + rename on commit(): atomic.
/// The destructor without commit() removes the temporary file; a writer killed before either
/// leaves it, and the next writer to PATH removes it (temporary_file.hpp says how it knows). add()
/// is thread-safe (one mutex; the payload write happens under it) and takes the blocks in any
/// order; every block of every level of the header's Partition must be added exactly once before
/// commit().
class AfamWriter {
 public:
  AfamWriter(const std::string& path, const VolumeHeader& header);
  ~AfamWriter();
  AfamWriter(const AfamWriter&) = delete;
  AfamWriter& operator=(const AfamWriter&) = delete;

  /// An uncoded model: payload holds its float32 control points (payloadBytes(entry.ncp) bytes; a
  /// Constant stores payload[0] only). entry's offset/size/checksum/storedSize are filled in here.
  /// Payloads are stored in the order they are added, 4-byte aligned.
  /// Throws InvalidArgument for a block out of range, added twice, or whose samples, kind, NCP or
  /// degree do not match the partition; IoError when the write fails.
  void add(const ModelEntry& entryWithoutOffsets, const float* payload);
  /// A model in its stored form: entry.storedSize bytes (coded payloads, or as add() stores them).
  void addStored(const ModelEntry& entryWithoutOffsets, const void* stored);
  /// Writes the index and header, fsyncs and renames onto the final path. Throws InvalidArgument
  /// if blocks are missing, IoError on failure (the temporary file is then removed).
  void commit();
  const VolumeHeader& header() const { return header_; }
  const Partition& partition() const { return partition_; }
  uint64_t bytesWritten() const;  ///< current end of the file (header + index + payloads so far)

 private:
  std::string path_, tmpPath_;
  int fd_ = -1;
  bool committed_ = false;
  VolumeHeader header_;
  Partition partition_;
  std::vector<int64_t> levelStart_;
  std::vector<ModelEntry> entries_;
  std::vector<uint8_t> present_;
  uint64_t end_ = 0, payloadOffset_ = 0;
  mutable std::mutex mutex_;
};

}  // namespace afam
