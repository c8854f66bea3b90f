// SPDX-License-Identifier: BSD-3-Clause
// Reading a file's samples by offset (pread), on any thread: the one place RawFileSource and
// HeaderVolumeSource read and convert their payloads (private to Core).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "afam/format/partition.hpp"
#include "afam/volume/sample_type.hpp"

namespace afam {

/// `bytes` bytes of `fd` from `offset` into dst; IoError naming `path` and the byte where a read
/// fails or the file ends.
void readFully(int fd, const std::string& path, uint64_t offset, unsigned char* dst,
               uint64_t bytes);

/// `count` samples of `type` from byte `offset` of `fd`, as floats (samplesToFloat; `swapBytes`:
/// big-endian data), read a few megabytes at a time into a buffer of the calling thread and
/// converted while they are in cache. float32 in this host's order is read straight into out.
void readFileSamples(int fd, const std::string& path, uint64_t offset, SampleType type,
                     uint64_t count, float* out, bool swapBytes = false);

/// The storedType of a source whose samples are of `type` in this host's order: the type where
/// it is an integer of 1 or 2 bytes (whose planes as floats would take 2 to 4 times the bytes),
/// else none.
std::optional<SampleType> storedAs(SampleType type);

/// Where rows [y0, y0 + yCount) of planes [z0, z0 + zCount) of a volume of `dims` samples of `es`
/// bytes lie: one run of bytes a plane (all of it for whole planes).
struct StoredRows {
  uint64_t first = 0;   ///< the first plane's first byte
  uint64_t run = 0;     ///< bytes a plane
  uint64_t stride = 0;  ///< from a plane's run to the next plane's
  int64_t planes = 0;   ///< runs (1 for whole planes: one run of them all)
};
/// Throws InvalidArgument naming `what` for rows or planes outside the volume.
StoredRows storedRows(const Index3& dims, int es, int64_t z0, int64_t zCount, int64_t y0,
                      int64_t yCount, const std::string& what);
/// Those rows' bytes from `fd` (from byte `base`) into out, one pread a run.
void readStoredFileRows(int fd, const std::string& path, uint64_t base, const StoredRows& rows,
                        void* out);
/// Those rows' bytes from a volume in memory into out.
void copyStoredRows(const unsigned char* volume, const StoredRows& rows, void* out);

}  // namespace afam
