// SPDX-License-Identifier: BSD-3-Clause
#include "afam/format/afam_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <sstream>

#include "afam/base/errors.hpp"
#include "afam/base/thread_scratch.hpp"
#include "afam/format/block_codec.hpp"
#include "afam/format/block_mask.hpp"
#include "afam/format/rounded_points.hpp"
#include "afam/format/temporary_file.hpp"
#include "afam/spline/fit.hpp"
#include "file_layout.hpp"

namespace afam {

#if defined(__BYTE_ORDER__) && (__BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__)
#error \
    "the .afam reader and writer copy little-endian structs byte for byte: little-endian hosts only"
#endif

namespace {

struct CrcTables {
  uint32_t t[8][256];
  CrcTables() {
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[0][i] = c;
    }
    for (uint32_t i = 0; i < 256; ++i)
      for (int s = 1; s < 8; ++s) t[s][i] = (t[s - 1][i] >> 8) ^ t[0][t[s - 1][i] & 0xFFu];
  }
};
const CrcTables& crcTables() {
  static const CrcTables tables;
  return tables;
}

}  // namespace

namespace layout {

std::string sysError() { return std::strerror(errno); }

void preadAll(int fd, void* out, uint64_t bytes, uint64_t offset, const std::string& path,
              const std::string& what) {
  auto* p = static_cast<char*>(out);
  uint64_t done = 0;
  while (done < bytes) {
    const ssize_t r =
        ::pread(fd, p + done, static_cast<size_t>(std::min<uint64_t>(bytes - done, 1u << 30)),
                static_cast<off_t>(offset + done));
    if (r < 0) {
      if (errno == EINTR) continue;
      throw IoError(path + ": cannot read " + what + ": " + sysError());
    }
    if (r == 0)
      throw FormatError(path + ": truncated: " + what + " ends at byte " +
                        std::to_string(offset + bytes) + " past the end of the file");
    done += static_cast<uint64_t>(r);
  }
}

void pwriteAll(int fd, const void* data, uint64_t bytes, uint64_t offset, const std::string& path) {
  const auto* p = static_cast<const char*>(data);
  uint64_t done = 0;
  while (done < bytes) {
    const ssize_t r =
        ::pwrite(fd, p + done, static_cast<size_t>(std::min<uint64_t>(bytes - done, 1u << 30)),
                 static_cast<off_t>(offset + done));
    if (r < 0) {
      if (errno == EINTR) continue;
      throw IoError(path + ": write failed: " + sysError());
    }
    done += static_cast<uint64_t>(r);
  }
}

/// NCP and degree a model of this kind must have on one axis of n samples.
struct AxisRule {
  int degree, ncpLo, ncpHi;
};
AxisRule axisRule(BlockKind kind, EncodingMode mode, int headerDegree, int n) {
  if (mode == EncodingMode::Downsampled) return {1, n + 2, n + 2};
  if (kind == BlockKind::Samples) return {effectiveDegree(1, n), n, n};
  const int p = effectiveDegree(headerDegree, n);
  if (kind == BlockKind::Constant || kind == BlockKind::Empty) return {p, p + 1, p + 1};
  if (kind == BlockKind::Interpolant) return {p, n, n};
  return {p, p + 1, n};
}

/// Empty when the model is valid for its block, else what is wrong.
std::string modelProblem(const ModelEntry& m, EncodingMode mode, int headerDegree,
                         const BlockExtent& e) {
  if (static_cast<uint8_t>(m.kind) > static_cast<uint8_t>(BlockKind::Empty))
    return "unknown block kind " + std::to_string(static_cast<int>(m.kind));
  if (mode == EncodingMode::Downsampled && (m.kind != BlockKind::Spline || m.coded || m.masked))
    return "a downsampled file holds raw samples only";
  if (m.kind == BlockKind::Empty && (m.coded || m.masked))
    return "an empty block has no payload and no mask";
  if (m.kind == BlockKind::Constant && m.coded) return "a constant block is never coded";
  if (m.kind == BlockKind::Interpolant && !m.coded) return "an interpolant block is always coded";
  if (m.roundedPoints && m.kind != BlockKind::Interpolant)
    return std::string("rounded points flagged on a ") + blockKindName(m.kind);
  for (int a = 0; a < 3; ++a) {
    const AxisRule r = axisRule(m.kind, mode, headerDegree, e.samples[a]);
    if (m.ncp[a] < r.ncpLo || m.ncp[a] > r.ncpHi || m.degree[a] != r.degree || m.ncp[a] > 65535)
      return std::string(blockKindName(m.kind)) + " NCP " + std::to_string(m.ncp[a]) +
             " / degree " + std::to_string(m.degree[a]) + " invalid on axis " + std::to_string(a) +
             " (NCP in [" + std::to_string(r.ncpLo) + ", " + std::to_string(r.ncpHi) +
             "], degree " + std::to_string(r.degree) + ")";
  }
  return {};
}

/// Stored bytes of an uncoded model.
uint64_t uncodedBytes(const ModelEntry& m) {
  if (m.kind == BlockKind::Empty) return 0;
  return m.kind == BlockKind::Constant ? 4 : payloadBytes(m.ncp);
}

/// Empty when the entry's stored size fits its kind and flags, else what is wrong: an uncoded
/// model's exact bytes, a coded payload's header and more, a masked one's mask section before
/// either (at least 8 bytes: its length and a zstd frame).
std::string storedSizeProblem(const ModelEntry& m) {
  const uint64_t mask = m.masked ? 8 : 0;
  const uint64_t codedMin = (m.integerCoded ? kIntegerCodedHeaderBytes : kCodedHeaderBytes) + 1 +
                            (m.roundedPoints ? kRoundedPointsBytes : 0);
  const bool ok = m.coded ? m.storedSize >= codedMin + mask
                          : (m.masked ? m.storedSize >= uncodedBytes(m) + mask
                                      : m.storedSize == uncodedBytes(m));
  if (ok && m.storedSize <= std::numeric_limits<uint32_t>::max()) return {};
  return "stored size " + std::to_string(m.storedSize) + " does not fit " +
         (m.masked  ? "a masked "
          : m.coded ? "a coded "
                    : "an uncoded ") +
         blockKindName(m.kind);
}

/// Empty when the header allows the entry's missing-sample forms (an empty block, a mask), else
/// what is wrong.
std::string missingProblem(const ModelEntry& m, const VolumeHeader& vh) {
  if (vh.missing != MissingKind::None || (m.kind != BlockKind::Empty && !m.masked)) return {};
  return std::string(m.masked ? "a masked block" : "an empty block") +
         " in a file without missing samples";
}

void parseEntry(const IndexEntryV1& r, uint32_t version, const VolumeHeader& vh,
                const BlockExtent& e, const std::string& where, ModelEntry& m,
                uint16_t extraFlags) {
  const auto bad = [&](const std::string& what) { return FormatError(where + ": " + what); };
  if (version == 1 && (r.flags != 0 || r.storedBytes != 0)) throw bad("unknown entry flags");
  if ((r.flags & ~uint16_t(0x3ff | kLanesFlag | kRoundedPointsFlag | extraFlags)) != 0)
    throw bad("unknown entry flags " + std::to_string(r.flags));
  m.kind = static_cast<BlockKind>(r.flags & 0xff);
  m.coded = (r.flags & 0x100) != 0;
  m.integerCoded = (r.flags & 0x200) != 0;
  m.lanesCoded = (r.flags & kLanesFlag) != 0;
  m.masked = (r.flags & kMaskedFlag) != 0;
  m.roundedPoints = (r.flags & kRoundedPointsFlag) != 0;
  if (m.integerCoded && !m.coded) throw bad("integer form flagged on an uncoded payload");
  if (m.lanesCoded && !m.coded) throw bad("lanes frame flagged on an uncoded payload");
  m.samples = e.samples;
  for (int a = 0; a < 3; ++a) {
    m.ncp[a] = r.ncp[a];
    m.degree[a] = axisRule(m.kind, vh.mode, vh.degree, e.samples[a]).degree;
  }
  std::string problem = modelProblem(m, vh.mode, vh.degree, e);
  if (problem.empty()) problem = missingProblem(m, vh);
  if (!problem.empty()) throw bad(problem);
  if (!checkedPayloadBytes(r.ncp, m.size)) throw bad("payload size overflows");
  m.size = decodedBytes(m);
  m.storedSize = version == 1 ? m.size : r.storedBytes;
  if (m.kind == BlockKind::Empty && (r.offset != 0 || r.checksum != 0))
    throw bad("an empty block with a payload");
  problem = storedSizeProblem(m);
  if (!problem.empty()) throw bad(problem);
}

void parseVolumeHeader(const FileHeader& h, const std::string& path, VolumeHeader& vh,
                       Partition& partition) {
  const auto bad = [&](const std::string& what) { return FormatError(path + ": " + what); };
  for (int a = 0; a < 3; ++a) {
    if (h.dims[a] < 1 || h.dims[a] > std::numeric_limits<int32_t>::max())
      throw bad("absurd dimension " + std::to_string(h.dims[a]) + " on axis " + std::to_string(a));
    vh.dims[a] = h.dims[a];
    vh.origin[a] = h.origin[a];
    vh.spacing[a] = h.spacing[a];
  }
  if (h.levels < 1 || h.levels > kMaxLevels)
    throw bad("absurd level count " + std::to_string(h.levels));
  if (h.blocksPerAxis < 1 || h.blocksPerAxis > 65535)
    throw bad("absurd blocks per axis " + std::to_string(h.blocksPerAxis));
  if (h.degree < 1 || h.degree > 5)
    throw bad("degree " + std::to_string(h.degree) + " outside [1, 5]");
  if (h.mode > static_cast<uint8_t>(EncodingMode::Downsampled))
    throw bad("unknown encoding mode " + std::to_string(h.mode));
  vh.valueMin = h.valueMin;
  vh.valueMax = h.valueMax;
  vh.levels = h.levels;
  vh.blocksPerAxis = h.blocksPerAxis;
  vh.degree = h.degree;
  vh.errorBound = h.errorBound;
  vh.relativeBound = h.relativeBound != 0;
  vh.boundKind = h.version >= 3 ? static_cast<BoundKind>(h.boundKind) : BoundKind::Rmse;
  if (h.version >= 3) {
    if (h.missingKind > static_cast<uint8_t>(MissingKind::Value))
      throw bad("missing-value kind " + std::to_string(h.missingKind) +
                " is not read by this version");
    vh.missing = static_cast<MissingKind>(h.missingKind);
    vh.missingValue = h.missingValue;
    if (vh.missing == MissingKind::Value && !std::isfinite(vh.missingValue))
      throw bad("missing value is not a finite number");
  }
  vh.mode = static_cast<EncodingMode>(h.mode);
  if (h.levelSampling > static_cast<uint8_t>(LevelSampling::Box))
    throw bad("unknown level sampling " + std::to_string(h.levelSampling));
  vh.sampling = static_cast<LevelSampling>(h.levelSampling);
  vh.sourceBytesPerSample = h.sourceBytesPerSample;
  vh.fixedNcp = h.fixedNcp;
  vh.scalarName.assign(h.scalarName, strnlen(h.scalarName, sizeof h.scalarName));

  partition = Partition(vh.dims, vh.levels, vh.blocksPerAxis);
  const Partition& part = partition;
  for (int l = 0; l < vh.levels; ++l) {
    const Int3 b = part.blocksPerAxis(l);
    for (int a = 0; a < 3; ++a)
      if (h.levelBlocks[l][a] != b[a])
        throw bad("blocks per axis of level " + std::to_string(l) + " disagree with the partition");
  }
}

std::vector<int64_t> levelStarts(const Partition& partition, int levels) {
  std::vector<int64_t> start(static_cast<size_t>(levels) + 1, 0);
  for (int l = 0; l < levels; ++l)
    start[static_cast<size_t>(l) + 1] = start[static_cast<size_t>(l)] + partition.blockCount(l);
  return start;
}

size_t checkModelToWrite(const std::string& path, const VolumeHeader& vh,
                         const Partition& partition, const std::vector<int64_t>& levelStart,
                         const ModelEntry& in) {
  const auto bad = [&](const std::string& what) {
    return InvalidArgument(path + ": " + Partition::blockName(in.level, in.block) + what);
  };
  if (in.level < 0 || in.level >= vh.levels)
    throw InvalidArgument(path + ": level " + std::to_string(in.level) + " out of range");
  const Int3 b = partition.blocksPerAxis(in.level);
  for (int a = 0; a < 3; ++a)
    if (in.block[a] < 0 || in.block[a] >= b[a]) throw bad(" out of range");
  const BlockExtent e = partition.extent(in.level, in.block);
  if (in.samples != e.samples) throw bad(": samples disagree with the partition");
  std::string problem = modelProblem(in, vh.mode, vh.degree, e);
  if (problem.empty()) problem = missingProblem(in, vh);
  if (problem.empty()) problem = storedSizeProblem(in);
  if (!problem.empty()) throw bad(": " + problem);
  return static_cast<size_t>(levelStart[static_cast<size_t>(in.level)] +
                             partition.linearIndex(in.level, in.block));
}

namespace {
/// Bytes of a stored payload's mask section (0 when unmasked).
size_t maskSkip(const ModelEntry& m, const uint8_t* bytes) {
  if (!m.masked || m.storedSize < 4) return 0;
  uint32_t coded = 0;
  std::memcpy(&coded, bytes, 4);
  return std::min<size_t>(maskSectionBytes(coded), m.storedSize);
}
}  // namespace

bool storedIsIntegerCoded(const ModelEntry& m, const void* stored) {
  const auto* bytes = static_cast<const uint8_t*>(stored);
  const size_t skip = maskSkip(m, bytes);
  return m.coded && payloadIsIntegerCoded(bytes + skip, m.storedSize - skip);
}

bool storedIsLanesCoded(const ModelEntry& m, const void* stored) {
  const auto* bytes = static_cast<const uint8_t*>(stored);
  const size_t skip = maskSkip(m, bytes);
  return m.coded && payloadIsLanesCoded(bytes + skip, m.storedSize - skip);
}

IndexEntryV1 rawEntry(const ModelEntry& m, uint16_t extraFlags) {
  IndexEntryV1 r;
  std::memset(&r, 0, sizeof r);
  r.offset = m.offset;
  for (int a = 0; a < 3; ++a) r.ncp[a] = static_cast<uint16_t>(m.ncp[a]);
  r.minValue = m.minValue;
  r.maxValue = m.maxValue;
  r.rmse = m.rmse;
  r.maxError = m.maxError;
  r.checksum = m.checksum;
  r.flags = static_cast<uint16_t>(static_cast<uint16_t>(m.kind) | (m.coded ? 0x100 : 0) |
                                  (m.integerCoded ? 0x200 : 0) | (m.lanesCoded ? kLanesFlag : 0) |
                                  (m.masked ? kMaskedFlag : 0) |
                                  (m.roundedPoints ? kRoundedPointsFlag : 0) | extraFlags);
  r.storedBytes = static_cast<uint32_t>(m.storedSize);
  if (m.kind == BlockKind::Empty) r.offset = r.checksum = r.storedBytes = 0;
  return r;
}

FileHeader makeFileHeader(const VolumeHeader& vh, const Partition& partition, uint32_t version) {
  FileHeader h;
  std::memset(&h, 0, sizeof h);
  std::memcpy(h.magic, kMagic, 8);
  h.version = version;
  h.endianTag = kEndianTag;
  h.headerSize = sizeof(FileHeader);
  h.entrySize = sizeof(IndexEntryV1);
  for (int a = 0; a < 3; ++a) {
    h.dims[a] = vh.dims[a];
    h.origin[a] = vh.origin[a];
    h.spacing[a] = vh.spacing[a];
  }
  h.valueMin = vh.valueMin;
  h.valueMax = vh.valueMax;
  h.errorBound = vh.errorBound;
  h.levels = vh.levels;
  h.blocksPerAxis = vh.blocksPerAxis;
  h.degree = vh.degree;
  h.fixedNcp = vh.fixedNcp;
  h.mode = static_cast<uint8_t>(vh.mode);
  h.relativeBound = vh.relativeBound ? 1 : 0;
  if (version >= 3) {
    h.boundKind = static_cast<uint8_t>(vh.boundKind);
    h.missingKind = static_cast<uint8_t>(vh.missing);
    h.missingValue = vh.missing == MissingKind::Value ? vh.missingValue : 0.0;
  }
  h.levelSampling = static_cast<uint8_t>(vh.sampling);
  h.sourceBytesPerSample = static_cast<uint8_t>(std::min(vh.sourceBytesPerSample, 255));
  std::strncpy(h.scalarName, vh.scalarName.c_str(), sizeof h.scalarName - 1);
  for (int l = 0; l < vh.levels; ++l) {
    const Int3 b = partition.blocksPerAxis(l);
    for (int a = 0; a < 3; ++a) h.levelBlocks[l][a] = b[a];
  }
  h.payloadAlignment = kPayloadAlign;
  return h;
}

void abandonTemporary(int& fd, std::string& tmpPath) {
  if (fd >= 0) ::close(fd);
  fd = -1;
  ::unlink(tmpPath.c_str());
  tmpPath.clear();
}

void renameIntoPlace(int& fd, std::string& tmpPath, const std::string& path) {
  try {
    if (::fsync(fd) != 0) throw IoError(tmpPath + ": fsync failed: " + sysError());
    // Rename while the descriptor (and so the lock) is still held: a closed, unlocked temporary
    // file would look abandoned to another writer's removeStaleTemporaries.
    if (::rename(tmpPath.c_str(), path.c_str()) != 0)
      throw IoError(path + ": cannot rename the temporary file onto it: " + sysError());
    ::close(fd);  // the data is already on disk (fsync); nothing is left to fail
    fd = -1;
  } catch (...) {
    abandonTemporary(fd, tmpPath);
    throw;
  }
  // Make the rename durable: fsync the directory (best effort).
  const size_t slash = path.find_last_of('/');
  const std::string dir =
      slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
}

}  // namespace layout

using namespace layout;

uint32_t crc32(const void* data, size_t bytes, uint32_t crc) {
  const auto& T = crcTables().t;
  const auto* p = static_cast<const uint8_t*>(data);
  crc = ~crc;
  while (bytes >= 8) {
    uint32_t lo, hi;
    std::memcpy(&lo, p, 4);
    std::memcpy(&hi, p + 4, 4);
    lo ^= crc;
    crc = T[7][lo & 0xFF] ^ T[6][(lo >> 8) & 0xFF] ^ T[5][(lo >> 16) & 0xFF] ^ T[4][lo >> 24] ^
          T[3][hi & 0xFF] ^ T[2][(hi >> 8) & 0xFF] ^ T[1][(hi >> 16) & 0xFF] ^ T[0][hi >> 24];
    p += 8;
    bytes -= 8;
  }
  while (bytes--) crc = T[0][(crc ^ *p++) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

uint64_t fileBytes(uint64_t entries, uint64_t payloadBytes) {
  return sizeof(FileHeader) + entries * sizeof(IndexEntryV1) + payloadBytes;
}

uint64_t payloadBytes(const Int3& ncp) {
  const int32_t n[3] = {ncp[0], ncp[1], ncp[2]};
  uint64_t out = 0;
  if (!checkedPayloadBytes(n, out))
    throw InvalidArgument("payload size: invalid or overflowing NCP");
  return out;
}

uint64_t decodedBytes(const ModelEntry& e) {
  if (e.kind == BlockKind::Empty) return 0;
  const uint64_t control = payloadBytes(e.ncp);
  if (!e.masked) return control;
  return control +
         4 * uint64_t(maskWordCount(int64_t(e.samples[0]) * e.samples[1] * int64_t(e.samples[2])));
}

uint64_t paperModelBytes(const Int3& ncp, const Int3& degree) {
  uint64_t knots = 0;
  for (int a = 0; a < 3; ++a) knots += static_cast<uint64_t>(ncp[a] + degree[a]);
  return 1 + (knots + uint64_t(ncp[0]) * uint64_t(ncp[1]) * uint64_t(ncp[2])) * 4;
}

const char* blockKindName(BlockKind kind) {
  switch (kind) {
    case BlockKind::Spline:
      return "spline";
    case BlockKind::Samples:
      return "samples";
    case BlockKind::Constant:
      return "constant";
    case BlockKind::Interpolant:
      return "interpolant";
    case BlockKind::Empty:
      return "empty";
  }
  return "unknown";
}

namespace {
/// Throws unless a coded payload's predictor form and frame agree with the index's flags.
void checkPayloadFlags(const ModelEntry& e, const uint8_t* stored, const std::string& where) {
  if (!e.coded || e.kind == BlockKind::Constant) return;
  if (e.integerCoded != payloadIsIntegerCoded(stored, e.storedSize))
    throw FormatError(where + ": coded payload's predictor disagrees with the index's flags");
  if (e.lanesCoded != payloadIsLanesCoded(stored, e.storedSize))
    throw FormatError(where + ": coded payload's frame disagrees with the index's flags");
}
}  // namespace

void interpolantPoints(const ModelEntry& e, const float* samples, float* out,
                       const std::string& where) {
  thread_local FitResult fit;
  try {
    threadFitter().fitInto(samples, e.ncp, e.ncp,
                           std::max({e.degree[0], e.degree[1], e.degree[2], 1}), false, fit);
  } catch (const Error& ex) {
    throw FormatError(where + ": interpolant does not decode: " + ex.what());
  }
  std::memcpy(out, fit.control.data(), size_t(controlCount(e)) * sizeof(float));
}

/// An interpolant's model into out: its coded samples decoded and the spline of the header's
/// degree fitted through them, its points rounded when the entry says so (their codes into
/// `codes` when it is not null). Returns the points' step (0: not rounded). `out` may be the
/// calling thread's ScratchSlot::Samples (where the samples are decoded: written after the fit)
/// and `codes` its ScratchSlot::Doubles (decodeValues' doubles: written after the decoding).
double decodeInterpolant(const ModelEntry& e, const uint8_t* stored, float* out, int64_t* codes,
                         const std::string& where) {
  const size_t count = size_t(controlCount(e));
  const size_t coded = e.storedSize - (e.roundedPoints ? kRoundedPointsBytes : 0);
  float* samples = threadScratch<float>(ScratchSlot::Samples, count);
  decodeValues(stored, coded, e.ncp, samples, where.c_str());
  interpolantPoints(e, samples, out, where);
  if (!e.roundedPoints) return 0;
  const double q = roundedPointStep(stored, e.storedSize, where.c_str());
  if (!roundPoints(out, count, q, codes))
    throw FormatError(where + ": interpolant's points do not round to its point step");
  return q;
}

void decodeStoredPayload(const ModelEntry& e, const uint8_t* stored, float* out,
                         const std::string& where) {
  if (e.kind == BlockKind::Empty) return;
  if (storedAsDecoded(e)) {  // the decision readVerifiedPayload makes before reading in place
    std::memcpy(out, stored, e.size);
    return;
  }
  if (e.masked) {  // the mask section, then the model as an unmasked entry stores it
    const size_t section =
        readMaskSection(stored, e.storedSize, e.samples, out + controlCount(e), where.c_str());
    ModelEntry model = e;
    model.masked = false;
    model.storedSize = e.storedSize - section;
    model.size = decodedBytes(model);
    if (!model.coded && model.storedSize != uncodedBytes(model))
      throw FormatError(where + ": masked payload's model is " + std::to_string(model.storedSize) +
                        " bytes, not " + std::to_string(uncodedBytes(model)));
    decodeStoredPayload(model, stored + section, out, where);
    return;
  }
  const size_t count = e.size / sizeof(float);
  checkPayloadFlags(e, stored, where);
  if (e.kind == BlockKind::Constant) {
    float c;
    std::memcpy(&c, stored, 4);
    std::fill(out, out + count, c);
  } else if (e.kind == BlockKind::Interpolant) {
    decodeInterpolant(e, stored, out, nullptr, where);
  } else if (e.coded) {
    decodeValues(stored, e.storedSize, e.ncp, out, where.c_str());
  } else {
    std::memcpy(out, stored, e.size);
  }
}

double absoluteBound(const VolumeHeader& h) {
  return h.relativeBound ? h.errorBound * (h.valueMax - h.valueMin) : h.errorBound;
}

const char* boundKindName(BoundKind kind) {
  return kind == BoundKind::MaxError ? "max_error" : "rmse";
}

const char* missingKindName(MissingKind kind) {
  return kind == MissingKind::Value ? "value" : kind == MissingKind::NaN ? "nan" : "none";
}

const char* modeName(EncodingMode mode) {
  switch (mode) {
    case EncodingMode::Adaptive:
      return "adaptive";
    case EncodingMode::InLevel:
      return "inlevel";
    case EncodingMode::Fixed:
      return "fixed";
    case EncodingMode::Downsampled:
      return "ds";
  }
  return "unknown";
}

EncodingMode parseMode(const std::string& name) {
  if (name == "adaptive") return EncodingMode::Adaptive;
  if (name == "inlevel") return EncodingMode::InLevel;
  if (name == "fixed") return EncodingMode::Fixed;
  if (name == "ds") return EncodingMode::Downsampled;
  throw InvalidArgument("unknown mode '" + name + "' (expected adaptive, inlevel, fixed or ds)");
}

// ------------------------------------------------------------------------------------------------
// Reader

AfamFile::~AfamFile() {
  if (fd_ >= 0) ::close(fd_);
}

std::shared_ptr<const AfamFile> AfamFile::open(const std::string& path, int64_t step) {
  std::shared_ptr<AfamFile> f(new AfamFile());
  f->path_ = path;
  f->fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (f->fd_ < 0) throw IoError(path + ": cannot open: " + sysError());
  struct stat st {};
  if (::fstat(f->fd_, &st) != 0) throw IoError(path + ": cannot stat: " + sysError());
  if (!S_ISREG(st.st_mode)) throw IoError(path + ": not a regular file");
  f->fileSize_ = static_cast<uint64_t>(st.st_size);
  f->identity_ = identityOfDescriptor(f->fd_);
  const auto bad = [&](const std::string& what) { return FormatError(path + ": " + what); };

  if (f->fileSize_ < sizeof(FileHeader)) {
    if (f->fileSize_ >= 8) {
      char m[8];
      preadAll(f->fd_, m, 8, 0, path, "magic");
      if (std::memcmp(m, kMagic, 8) != 0) throw bad("not an .afam file (bad magic)");
    }
    throw bad("truncated: " + std::to_string(f->fileSize_) + " bytes, the header alone needs " +
              std::to_string(sizeof(FileHeader)));
  }
  FileHeader h{};
  preadAll(f->fd_, &h, sizeof h, 0, path, "header");
  if (std::memcmp(h.magic, kMagic, 8) != 0) throw bad("not an .afam file (bad magic)");
  if (h.endianTag != kEndianTag) throw bad("unsupported byte order (endianness tag mismatch)");
  if (h.version != 1 && h.version != kVersion && h.version != kRunVersion)
    throw bad("unsupported format version " + std::to_string(h.version) +
              " (this reader knows versions 1, 2 and 3)");
  if (crc32(&h, offsetof(FileHeader, headerChecksum)) != h.headerChecksum)
    throw bad("header checksum mismatch (header damaged)");
  if (h.headerSize != sizeof(FileHeader) || h.entrySize != sizeof(IndexEntryV1))
    throw bad("header or index entry size does not match version " + std::to_string(h.version));
  if (h.payloadAlignment < 4 || h.payloadAlignment > 4096 ||
      (h.payloadAlignment & (h.payloadAlignment - 1)) != 0)
    throw bad("payload alignment " + std::to_string(h.payloadAlignment) +
              " is not a power of two in [4, 4096]");

  parseVolumeHeader(h, path, f->header_, f->partition_);
  f->version_ = h.version;
  const VolumeHeader& vh = f->header_;
  const Partition& part = f->partition_;
  f->levelStart_ = levelStarts(part, vh.levels);
  if (h.version == kRunVersion) {
    openRunStep(*f, h, step);
    return f;
  }
  if (step != 0)
    throw InvalidArgument(path + ": step " + std::to_string(step) + " of a file of one step");
  if (h.fileSize != f->fileSize_)
    throw bad(h.fileSize > f->fileSize_
                  ? "truncated: " + std::to_string(f->fileSize_) + " bytes, header says " +
                        std::to_string(h.fileSize)
                  : "file has " + std::to_string(f->fileSize_) + " bytes, header says " +
                        std::to_string(h.fileSize) + " (trailing garbage)");
  const uint64_t expected = static_cast<uint64_t>(part.totalBlockCount());
  if (h.entryCount != expected)
    throw bad("index count " + std::to_string(h.entryCount) + " does not match the " +
              std::to_string(expected) + " blocks of the partition");
  if (h.indexOffset != sizeof(FileHeader))
    throw bad("index offset " + std::to_string(h.indexOffset) + " invalid");
  // Overflow-safe: the index must fit between its offset and the payload start, inside the file.
  if (h.entryCount > (f->fileSize_ - h.indexOffset) / sizeof(IndexEntryV1))
    throw bad("truncated: index of " + std::to_string(h.entryCount) +
              " entries runs past the end of the file");
  const uint64_t indexBytes = h.entryCount * sizeof(IndexEntryV1);
  if (h.payloadOffset < h.indexOffset + indexBytes || h.payloadOffset > f->fileSize_ ||
      h.payloadOffset % kAlign != 0)
    throw bad("payload offset " + std::to_string(h.payloadOffset) + " invalid");
  f->payloadOffset_ = h.payloadOffset;

  std::vector<IndexEntryV1> raw(h.entryCount);
  preadAll(f->fd_, raw.data(), indexBytes, h.indexOffset, path, "index");
  if (crc32(raw.data(), indexBytes) != h.indexChecksum)
    throw bad("index checksum mismatch (index damaged)");

  f->entries_.resize(raw.size());
  uint64_t payloadSum = 0;
  int level = 0;
  for (size_t i = 0; i < raw.size(); ++i) {
    while (static_cast<int64_t>(i) >= f->levelStart_[static_cast<size_t>(level) + 1]) ++level;
    const IndexEntryV1& r = raw[i];
    const Int3 ijk = part.blockFromLinear(
        level, static_cast<int64_t>(i) - f->levelStart_[static_cast<size_t>(level)]);
    const std::string where =
        "index entry " + std::to_string(i) + " (" + Partition::blockName(level, ijk) + ")";
    ModelEntry& m = f->entries_[i];
    m.level = level;
    m.block = ijk;
    parseEntry(r, h.version, vh, part.extent(level, ijk), path + ": " + where, m);
    if (r.offset < h.payloadOffset || r.offset % h.payloadAlignment != 0 ||
        r.offset > f->fileSize_ || m.storedSize > f->fileSize_ - r.offset)
      throw bad(where + ": payload [" + std::to_string(r.offset) + ", +" +
                std::to_string(m.storedSize) +
                ") lies outside the payload area or is misaligned (file size " +
                std::to_string(f->fileSize_) + ")");
    const uint64_t bytes = m.storedSize;
    payloadSum += bytes;
    m.offset = r.offset;
    m.minValue = r.minValue;
    m.maxValue = r.maxValue;
    m.rmse = r.rmse;
    m.maxError = r.maxError;
    m.checksum = r.checksum;
  }
  if (payloadSum != h.totalPayloadBytes)
    throw bad("payload sizes do not add up to the header's total");
  return f;
}

bool startsWithAfamMagic(const std::string& path) {
  char m[8] = {};
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  const ssize_t r = ::pread(fd, m, sizeof m, 0);
  ::close(fd);
  return r == ssize_t(sizeof m) && std::memcmp(m, kMagic, sizeof m) == 0;
}

int64_t AfamFile::entryIndex(int level, Int3 ijk) const {
  if (level < 0 || level >= header_.levels) return -1;
  const Int3 b = partition_.blocksPerAxis(level);
  for (int a = 0; a < 3; ++a)
    if (ijk[a] < 0 || ijk[a] >= b[a]) return -1;
  return levelStart_[static_cast<size_t>(level)] + partition_.linearIndex(level, ijk);
}

void AfamFile::throwIfChanged(const FileIdentity& now) const {
  const std::string change = describeChange(identity_, now);
  if (!change.empty())
    throw FileChangedError(path_ + ": the file changed since it was opened (" + change +
                           "); nothing more is read from it until it is opened again");
}

void AfamFile::checkUnchanged() const {
  throwIfChanged(identityOfDescriptor(fd_));
  throwIfChanged(identityOfPath(path_));
}

void AfamFile::readPayload(int64_t entry, void* out) const { readPayloadOnto(entry, nullptr, out); }

template <typename Read>
void AfamFile::readUnlessChanged(Read&& read) const {
  try {
    read();
  } catch (const FormatError&) {
    throwIfChanged(identityOfDescriptor(fd_));
    throw;
  }
  throwIfChanged(identityOfDescriptor(fd_));
}

const ModelEntry& AfamFile::entryAt(int64_t entry) const {
  if (entry < 0 || entry >= static_cast<int64_t>(entries_.size()))
    throw InvalidArgument(path_ + ": entry " + std::to_string(entry) + " out of range");
  return entries_[static_cast<size_t>(entry)];
}

void AfamFile::readChecked(const ModelEntry& e, void* out, size_t bytes) const {
  preadAll(fd_, out, bytes, e.offset, path_,
           "payload of " + Partition::blockName(e.level, e.block));
  if (crc32(out, bytes) != e.checksum)
    throw FormatError(path_ + ": payload checksum mismatch at " +
                      Partition::blockName(e.level, e.block));
}

void AfamFile::readPayloadOnto(int64_t entry, const float* previous, void* out) const {
  readUnlessChanged([&] { readVerifiedPayload(entry, previous, out); });
}

CompactForm AfamFile::readCompact(int64_t entry, double maxShare, std::vector<float>& out) const {
  const ModelEntry& e = entryAt(entry);
  if (e.roundedPoints && !e.masked && !e.residual) return readRoundedCompact(e, maxShare, out);
  if (!e.coded || !e.integerCoded || e.masked || e.residual ||
      (e.kind != BlockKind::Spline && e.kind != BlockKind::Samples) ||
      header_.mode == EncodingMode::Downsampled) {
    out.resize(e.size / sizeof(float));
    readPayload(entry, out.data());
    return CompactForm{};
  }
  const std::string where = path_ + ": " + Partition::blockName(e.level, e.block);
  CompactForm form;
  readUnlessChanged([&] {
    uint8_t* stored = threadScratch<uint8_t>(ScratchSlot::Stored, e.storedSize);
    readChecked(e, stored, e.storedSize);
    checkPayloadFlags(e, stored, where);
    form = decodeValuesCompact(stored, e.storedSize, e.ncp, maxShare, out, where.c_str());
  });
  return form;
}

CompactForm AfamFile::readRoundedCompact(const ModelEntry& e, double maxShare,
                                         std::vector<float>& out) const {
  const std::string where = path_ + ": " + Partition::blockName(e.level, e.block);
  const size_t count = size_t(controlCount(e));
  CompactForm form;
  readUnlessChanged([&] {
    uint8_t* stored = threadScratch<uint8_t>(ScratchSlot::Stored, e.storedSize);
    readChecked(e, stored, e.storedSize);
    checkPayloadFlags(e, stored, where);
    // Into scratch, so that `out` is allocated once, at the size of the form it keeps: the points
    // where decodeInterpolant decodes the samples (the fit has read them when the points are
    // written), their codes where decodeValues keeps its doubles (done with them by then): a thread
    // decoding an interpolant holds two block-sized buffers, not four (the cache's budget counts
    // them). The same sizes as decodeInterpolant asks of those slots, so neither moves.
    float* points = threadScratch<float>(ScratchSlot::Samples, count);
    int64_t* codes = threadScratch<int64_t>(ScratchSlot::Doubles, count);
    const double q = decodeInterpolant(e, stored, points, codes, where);
    form = packCompact(
        codes, count, maxShare, [q](int64_t k) { return pointValue(k, q); }, out);
    if (form.width == 0) out.assign(points, points + count);
  });
  return form;
}

std::vector<uint8_t> AfamFile::readStored(int64_t entry) const {
  const ModelEntry& e = entryAt(entry);
  if (e.residual || e.kind == BlockKind::Empty)
    throw InvalidArgument(path_ + ": " + Partition::blockName(e.level, e.block) +
                          " is not stored as one payload");
  std::vector<uint8_t> stored(e.storedSize);
  readUnlessChanged([&] { readChecked(e, stored.data(), stored.size()); });
  return stored;
}

void AfamFile::readVerifiedPayload(int64_t entry, const float* previous, void* out) const {
  const ModelEntry& e = entryAt(entry);
  const std::string where = path_ + ": " + Partition::blockName(e.level, e.block);
  if (e.residual) {  // its chain of payloads in time
    decodeChain(fd_, path_, e, chain(entry), previous, static_cast<float*>(out));
    return;
  }
  if (e.kind == BlockKind::Empty) return;  // no payload
  if (storedAsDecoded(e)) {                // uncoded floats: read in place
    readChecked(e, out, e.size);
    return;
  }
  uint8_t* stored = threadScratch<uint8_t>(ScratchSlot::Stored, e.storedSize);
  readChecked(e, stored, e.storedSize);
  decodeStoredPayload(e, stored, static_cast<float*>(out), where);
}

const std::vector<PayloadPart>& AfamFile::chain(int64_t entry) const {
  static const std::vector<PayloadPart> none;
  const auto it = chains_.find(entry);
  return it == chains_.end() ? none : it->second;
}

std::vector<float> AfamFile::readPayload(int64_t entry) const {
  if (entry < 0 || entry >= static_cast<int64_t>(entries_.size()))
    throw InvalidArgument(path_ + ": entry " + std::to_string(entry) + " out of range");
  std::vector<float> out(entries_[static_cast<size_t>(entry)].size / 4);
  readPayload(entry, out.data());
  return out;
}

// ------------------------------------------------------------------------------------------------
// Writer

AfamWriter::AfamWriter(const std::string& path, const VolumeHeader& header)
    : path_(path), header_(header) {
  if (header.boundKind != BoundKind::Rmse || header.missing != MissingKind::None)
    throw InvalidArgument(
        std::string("writer: ") +
        (header.missing != MissingKind::None ? "missing samples are" : "a pointwise bound is") +
        " kept by version-3 files (RunWriter), not version 2");
  if (header.degree < 1 || header.degree > 5)
    throw InvalidArgument("writer: degree " + std::to_string(header.degree) + " outside [1, 5]");
  if (header.levels > kMaxLevels) throw InvalidArgument("writer: more than 16 levels");
  partition_ = Partition(header.dims, header.levels, header.blocksPerAxis);
  const int64_t total = partition_.totalBlockCount();
  if (total > (int64_t(1) << 31)) throw InvalidArgument("writer: more than 2^31 micro-blocks");
  levelStart_.resize(static_cast<size_t>(header.levels) + 1, 0);
  for (int l = 0; l < header.levels; ++l)
    levelStart_[static_cast<size_t>(l) + 1] =
        levelStart_[static_cast<size_t>(l)] + partition_.blockCount(l);
  entries_.resize(static_cast<size_t>(total));
  present_.assign(static_cast<size_t>(total), 0);
  payloadOffset_ =
      alignUp(sizeof(FileHeader) + static_cast<uint64_t>(total) * sizeof(IndexEntryV1));
  for (int a = 0; a < 3; ++a)
    if (partition_.extent(header.levels - 1, {0, 0, 0}).samples[a] > 65533 ||
        partition_.extent(0, {0, 0, 0}).samples[a] > 65533)
      throw InvalidArgument(
          "writer: micro-blocks of more than 65533 samples per axis (use more blocks)");
  end_ = payloadOffset_;

  removeStaleTemporaries(path);                 // left by writers killed before they finished
  fd_ = createLockedTemporary(path, tmpPath_);  // locked until the rename (temporary_file.hpp)
}

AfamWriter::~AfamWriter() {
  if (fd_ >= 0) ::close(fd_);
  if (!committed_ && !tmpPath_.empty()) ::unlink(tmpPath_.c_str());
}

uint64_t AfamWriter::bytesWritten() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return end_;
}

void AfamWriter::add(const ModelEntry& in, const float* payload) {
  ModelEntry e = in;
  e.coded = false;
  e.storedSize = uncodedBytes(e);
  addStored(e, payload);
}

void AfamWriter::addStored(const ModelEntry& in, const void* stored) {
  const size_t slot = checkModelToWrite(path_, header_, partition_, levelStart_, in);
  const uint64_t bytes = in.storedSize;
  const uint32_t crc = crc32(stored, bytes);
  std::lock_guard<std::mutex> lock(mutex_);
  if (committed_) throw InvalidArgument(path_ + ": add() after commit()");
  if (present_[slot])
    throw InvalidArgument(path_ + ": " + Partition::blockName(in.level, in.block) + " added twice");
  const uint64_t offset = end_;
  pwriteAll(fd_, stored, bytes, offset, tmpPath_);
  end_ = alignUp(offset + bytes, kPayloadAlign);
  ModelEntry& m = entries_[slot];
  m = in;
  m.integerCoded = storedIsIntegerCoded(in, stored);
  m.lanesCoded = storedIsLanesCoded(in, stored);
  m.offset = offset;
  m.size = decodedBytes(in);
  m.checksum = crc;
  present_[slot] = 1;
}

void AfamWriter::commit() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (committed_) return;
  for (size_t i = 0; i < present_.size(); ++i)
    if (!present_[i]) {
      int level = 0;
      while (static_cast<int64_t>(i) >= levelStart_[static_cast<size_t>(level) + 1]) ++level;
      const Int3 ijk = partition_.blockFromLinear(
          level, static_cast<int64_t>(i) - levelStart_[static_cast<size_t>(level)]);
      throw InvalidArgument(path_ + ": commit without " + Partition::blockName(level, ijk));
    }
  std::vector<IndexEntryV1> raw(entries_.size());
  uint64_t payloadSum = 0;
  for (size_t i = 0; i < entries_.size(); ++i) {
    const ModelEntry& m = entries_[i];
    raw[i] = rawEntry(m, 0);
    payloadSum += m.storedSize;
  }
  const uint64_t indexBytes = raw.size() * sizeof(IndexEntryV1);
  const uint64_t fileSize = end_;
  FileHeader h = makeFileHeader(header_, partition_, kVersion);
  h.indexChecksum = crc32(raw.data(), indexBytes);
  h.entryCount = raw.size();
  h.indexOffset = sizeof(FileHeader);
  h.payloadOffset = payloadOffset_;
  h.fileSize = fileSize;
  h.totalPayloadBytes = payloadSum;
  h.headerChecksum = crc32(&h, offsetof(FileHeader, headerChecksum));
  commitTemporary(fd_, tmpPath_, path_, fileSize, [&] {
    pwriteAll(fd_, raw.data(), indexBytes, sizeof(FileHeader), tmpPath_);
    pwriteAll(fd_, &h, sizeof h, 0, tmpPath_);
  });
  committed_ = true;
}

}  // namespace afam
