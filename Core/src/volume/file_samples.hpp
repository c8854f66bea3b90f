// SPDX-License-Identifier: BSD-3-Clause
// Reading a file's samples by offset (pread), on any thread: the one place RawFileSource and
// HeaderVolumeSource read and convert their payloads (private to Core).
#pragma once

#include <cstdint>
#include <string>

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

}  // namespace afam
