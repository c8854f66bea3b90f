// SPDX-License-Identifier: BSD-3-Clause
// The .afam file's on-disk structs and the checks every version shares (docs/FORMAT.md), for the
// single-step reader and writer (afam_file.cpp) and the run of steps of version 3 (run_file.cpp).
// Internal to Core/src/format.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/format/afam_file.hpp"

namespace afam::layout {

inline constexpr char kMagic[8] = {'A', 'F', 'A', 'M', '\r', '\n', '\x1a', '\n'};
constexpr uint32_t kVersion = 2;     // written for one step; version 1 is still read
constexpr uint32_t kRunVersion = 3;  // written for a run of steps
constexpr uint32_t kEndianTag = 0x01020304u;
constexpr uint64_t kAlign = 64;        // start of the payload area
constexpr uint32_t kPayloadAlign = 4;  // payload offsets (float32 arrays, uploaded unchanged)
constexpr int kMaxLevels = 16;
constexpr uint16_t kLanesFlag = 1u << 13;  // entry flags bit 13: the coded payload's frame is lanes
constexpr uint16_t kMaskedFlag = 1u << 12;  // v3 entry flags bit 12: the payload starts with a mask
constexpr uint16_t kRoundedPointsFlag = 1u << 14;  // bit 14: an interpolant's points are rounded

// On-disk header of versions 1, 2 and 3 (one layout; docs/FORMAT.md): 1024 bytes, little-endian;
// each member's byte offset and size beside it (@offset, size), checked by the static_asserts
// below.
struct FileHeader {
  char magic[8];                 // @0, 8 B
  uint32_t version;              // @8, 4 B
  uint32_t endianTag;            // @12, 4 B
  uint32_t headerSize;           // @16, 4 B
  uint32_t entrySize;            // @20, 4 B
  int64_t dims[3];               // @24, 24 B
  double origin[3];              // @48, 24 B
  double spacing[3];             // @72, 24 B
  double valueMin;               // @96, 8 B
  double valueMax;               // @104, 8 B
  double errorBound;             // @112, 8 B
  int32_t levels;                // @120, 4 B
  int32_t blocksPerAxis;         // @124, 4 B
  int32_t degree;                // @128, 4 B
  int32_t fixedNcp;              // @132, 4 B
  uint8_t mode;                  // @136, 1 B
  uint8_t relativeBound;         // @137, 1 B
  uint8_t levelSampling;         // @138, 1 B; LevelSampling: 0 point (older files), 1 box
  uint8_t sourceBytesPerSample;  // @139, 1 B; bytes of one sample of the encoded input (0: unknown)
  uint32_t indexChecksum;        // @140, 4 B
  uint64_t entryCount;           // @144, 8 B
  uint64_t indexOffset;          // @152, 8 B
  uint64_t payloadOffset;        // @160, 8 B
  uint64_t fileSize;             // @168, 8 B
  char scalarName[64];           // @176, 64 B
  int32_t levelBlocks[kMaxLevels][3];  // @240, 192 B
  uint64_t totalPayloadBytes;          // @432, 8 B
  uint32_t payloadAlignment;           // @440, 4 B; a power of two in [4, 4096] that every payload
                                       // offset is a multiple of
  uint32_t keyInterval;                // @444, 4 B; v3: K, a key step at least every K steps
  double absoluteBound;                // @448, 8 B; v3: the bound in the data's units
  uint8_t boundKind;                   // @456, 1 B; v3: 0 RMSE per block, 1 max error per sample
  uint8_t missingKind;                 // @457, 1 B; v3: 0 none, 1 NaN, 2 missingValue
  uint8_t reserved2[6];                // @458, 6 B
  double missingValue;                 // @464, 8 B; v3: the fill value with missingKind 2
  uint8_t reserved3[548];              // @472, 548 B
  uint32_t headerChecksum;             // @1020, 4 B; CRC32 of bytes [0, 1020)
};
static_assert(sizeof(FileHeader) == 1024, "header size");
static_assert(offsetof(FileHeader, version) == 8, "layout");
static_assert(offsetof(FileHeader, endianTag) == 12, "layout");
static_assert(offsetof(FileHeader, headerSize) == 16, "layout");
static_assert(offsetof(FileHeader, entrySize) == 20, "layout");
static_assert(offsetof(FileHeader, dims) == 24, "layout");
static_assert(offsetof(FileHeader, origin) == 48, "layout");
static_assert(offsetof(FileHeader, spacing) == 72, "layout");
static_assert(offsetof(FileHeader, valueMin) == 96, "layout");
static_assert(offsetof(FileHeader, valueMax) == 104, "layout");
static_assert(offsetof(FileHeader, errorBound) == 112, "layout");
static_assert(offsetof(FileHeader, levels) == 120, "layout");
static_assert(offsetof(FileHeader, blocksPerAxis) == 124, "layout");
static_assert(offsetof(FileHeader, degree) == 128, "layout");
static_assert(offsetof(FileHeader, fixedNcp) == 132, "layout");
static_assert(offsetof(FileHeader, mode) == 136, "layout");
static_assert(offsetof(FileHeader, relativeBound) == 137, "layout");
static_assert(offsetof(FileHeader, levelSampling) == 138, "layout");
static_assert(offsetof(FileHeader, sourceBytesPerSample) == 139, "layout");
static_assert(offsetof(FileHeader, indexChecksum) == 140, "layout");
static_assert(offsetof(FileHeader, entryCount) == 144, "layout");
static_assert(offsetof(FileHeader, indexOffset) == 152, "layout");
static_assert(offsetof(FileHeader, payloadOffset) == 160, "layout");
static_assert(offsetof(FileHeader, fileSize) == 168, "layout");
static_assert(offsetof(FileHeader, scalarName) == 176, "layout");
static_assert(offsetof(FileHeader, levelBlocks) == 240, "layout");
static_assert(offsetof(FileHeader, totalPayloadBytes) == 432, "layout");
static_assert(offsetof(FileHeader, payloadAlignment) == 440, "layout");
static_assert(offsetof(FileHeader, keyInterval) == 444, "layout");
static_assert(offsetof(FileHeader, absoluteBound) == 448, "layout");
static_assert(offsetof(FileHeader, boundKind) == 456, "layout");
static_assert(offsetof(FileHeader, missingKind) == 457, "layout");
static_assert(offsetof(FileHeader, missingValue) == 464, "layout");
static_assert(offsetof(FileHeader, reserved3) == 472, "layout");
static_assert(offsetof(FileHeader, headerChecksum) == 1020, "layout");

// On-disk index entry, version 1: 40 bytes, each member's offset and size beside it. Level, block
// ijk, samples and degree are implied by the entry's position (the index is complete and ordered)
// and the header; the payload size by the NCP. Keeping the entry this small is what makes the
// file smaller than the paper's layout even for the smallest models (NCP 3: 108 + 40 bytes
// against 169).
struct IndexEntryV1 {
  uint64_t offset;    // @0, 8 B
  uint16_t ncp[3];    // @8, 6 B
  uint16_t flags;     // @14, 2 B; v2: bits 0-7 BlockKind, bit 8 coded, bit 9 integer form; v1: 0.
                      // Other bits: an unknown feature
  float minValue;     // @16, 4 B
  float maxValue;     // @20, 4 B
  float rmse;         // @24, 4 B
  float maxError;     // @28, 4 B
  uint32_t checksum;  // @32, 4 B
  uint32_t storedBytes;  // @36, 4 B; v2: payload bytes on disk; v1: 0 (the payload is
                         // the NCP's floats)
};
static_assert(sizeof(IndexEntryV1) == 40, "entry size");
static_assert(offsetof(IndexEntryV1, ncp) == 8, "layout");
static_assert(offsetof(IndexEntryV1, flags) == 14, "layout");
static_assert(offsetof(IndexEntryV1, minValue) == 16, "layout");
static_assert(offsetof(IndexEntryV1, maxValue) == 20, "layout");
static_assert(offsetof(IndexEntryV1, rmse) == 24, "layout");
static_assert(offsetof(IndexEntryV1, maxError) == 28, "layout");
static_assert(offsetof(IndexEntryV1, checksum) == 32, "layout");
static_assert(offsetof(IndexEntryV1, storedBytes) == 36, "layout");

/// 64-byte alignment of the payload area's start (a multiple of it).
inline uint64_t alignUp(uint64_t v, uint64_t a = kAlign) { return (v + a - 1) / a * a; }

// Checked product of three non-negative ints times 4 (payload bytes); false on overflow.
template <typename Int>
bool checkedPayloadBytes(const Int ncp[3], uint64_t& out) {
  uint64_t v = 4;
  for (int a = 0; a < 3; ++a) {
    if (ncp[a] < 1) return false;
    const uint64_t f = static_cast<uint64_t>(ncp[a]);
    if (v > std::numeric_limits<uint64_t>::max() / f) return false;
    v *= f;
  }
  out = v;
  return true;
}

std::string sysError();
/// Reads `bytes` at `offset`; IoError on failure, FormatError ("truncated: <what> ...") at the end.
void preadAll(int fd, void* out, uint64_t bytes, uint64_t offset, const std::string& path,
              const std::string& what);
void pwriteAll(int fd, const void* data, uint64_t bytes, uint64_t offset, const std::string& path);
/// Empty when the model is valid for its block, else what is wrong.
std::string modelProblem(const ModelEntry& m, EncodingMode mode, int headerDegree,
                         const BlockExtent& e);
/// Stored bytes of an uncoded model.
uint64_t uncodedBytes(const ModelEntry& m);
/// An entry's kind, NCP, degree, sizes and flags (bits 0-9; `extraFlags` more bits allowed, left
/// for the caller) checked against its block; FormatError naming `where`.
void parseEntry(const IndexEntryV1& r, uint32_t version, const VolumeHeader& vh,
                const BlockExtent& e, const std::string& where, ModelEntry& m,
                uint16_t extraFlags = 0);
/// The volume's description from a header whose magic, version and checksum were checked, the
/// partition included; FormatError naming `path` when a field is absurd.
void parseVolumeHeader(const FileHeader& h, const std::string& path, VolumeHeader& vh,
                       Partition& partition);
/// The index slot of a model a writer is given, after checking its level, block, samples, kind,
/// NCP, degree and stored size against the header (InvalidArgument naming `path` and the block).
size_t checkModelToWrite(const std::string& path, const VolumeHeader& vh,
                         const Partition& partition, const std::vector<int64_t>& levelStart,
                         const ModelEntry& in);
/// The model of a residual entry into out (entry.size bytes): each payload of its chain (the
/// independent one first) read, checked against its CRC and decoded, the residuals added to the
/// first in order (payload_chain.cpp); or, given `previous` (the model of the chain without its
/// newest payload, as this function decoded it), the newest residual only, added to it: the same
/// floats. FormatError naming the path, block and step of a damaged payload.
void decodeChain(int fd, const std::string& path, const ModelEntry& e,
                 const std::vector<PayloadPart>& chain, const float* previous, float* out);
/// Whether a stored payload is coded in an integer form (index flag bit 9), looking past a masked
/// payload's mask section.
bool storedIsIntegerCoded(const ModelEntry& m, const void* stored);
/// Whether its coded payload's frame is a lanes frame (index flag bit 13).
bool storedIsLanesCoded(const ModelEntry& m, const void* stored);
/// The on-disk entry of a model, `extraFlags` or-ed into its flags.
IndexEntryV1 rawEntry(const ModelEntry& m, uint16_t extraFlags);
/// A header with the volume's description, the partition and `version` (checksum not set).
FileHeader makeFileHeader(const VolumeHeader& vh, const Partition& partition, uint32_t version);
/// Closes and removes a writer's temporary file after a failure.
void abandonTemporary(int& fd, std::string& tmpPath);
/// fsyncs the temporary file, renames it onto `path` (fd still open, so its lock holds), closes
/// it and fsyncs the directory; on failure closes and removes the temporary file and rethrows.
void renameIntoPlace(int& fd, std::string& tmpPath, const std::string& path);
/// A writer's last steps: sets the temporary file's size, runs `writes` (index, header...), then
/// renameIntoPlace; on failure the temporary file is removed and the error rethrown.
template <typename Writes>
void commitTemporary(int& fd, std::string& tmpPath, const std::string& path, uint64_t size,
                     Writes&& writes) {
  try {
    if (::ftruncate(fd, static_cast<off_t>(size)) != 0)
      throw IoError(tmpPath + ": cannot set file size: " + sysError());
    writes();
  } catch (...) {
    abandonTemporary(fd, tmpPath);
    throw;
  }
  renameIntoPlace(fd, tmpPath, path);
}
/// Version 3: reads the commit slots, the step table and step `step`'s index into `file`
/// (run_file.cpp), references resolved to the entries that hold their payloads.
void openRunStep(AfamFile& file, const FileHeader& header, int64_t step);
/// The first entry of each level, and the total, for a partition.
std::vector<int64_t> levelStarts(const Partition& partition, int levels);

}  // namespace afam::layout
