// SPDX-License-Identifier: BSD-3-Clause
// Test helper: a whole file's bytes, read and written back (to damage copies of .afam files).
#pragma once

#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "afam/format/afam_file.hpp"

namespace afam_test {

inline std::vector<char> readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<char>(std::istreambuf_iterator<char>(in), {});
}

inline void writeAll(const std::string& path, const std::vector<char>& b) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(b.data(), std::streamsize(b.size()));
}

/// Rewrites `n` bytes at `field` of index entry `entry` of a one-step file's bytes (entries of 40
/// bytes from offset 1024) and both checksums, so that the reader reaches the field's own check.
inline void patchIndex(std::vector<char>& b, size_t entry, size_t field, const void* v, size_t n) {
  uint64_t count;
  std::memcpy(&count, &b[144], 8);
  std::memcpy(&b[1024 + entry * 40 + field], v, n);
  const uint32_t icrc = afam::crc32(&b[1024], size_t(count) * 40);
  std::memcpy(&b[140], &icrc, 4);
  const uint32_t crc = afam::crc32(b.data(), 1020);
  std::memcpy(&b[1020], &crc, 4);
}

}  // namespace afam_test
