// SPDX-License-Identifier: BSD-3-Clause
// Recomputes the checksums of a (possibly mutated) .afam image in place, so that mutations reach
// the code behind the checks (index validation, payload reads, decoding) instead of stopping at
// "checksum mismatch". Knows the layouts of docs/FORMAT.md: header CRC at byte 1020 over [0, 1020),
// version at 8, index CRC at 140, entry count at 144, index offset at 152, 40-byte entries with the
// payload offset at +0, NCP (3 x uint16) at +8, the payload CRC at +32 and (version 2) the stored
// payload bytes at +36; version 1 payloads are the NCP's float32 control points.
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

#include "afam/format/afam_file.hpp"

namespace afam_fuzz {

enum ChecksumFix : uint8_t { kFixHeader = 1, kFixIndex = 2, kFixPayloads = 4 };

template <typename T>
T loadAt(const std::vector<uint8_t>& b, size_t at) {
  T v{};
  std::memcpy(&v, b.data() + at, sizeof v);
  return v;
}
template <typename T>
void storeAt(std::vector<uint8_t>& b, size_t at, T v) {
  std::memcpy(b.data() + at, &v, sizeof v);
}

inline void fixAfamChecksums(std::vector<uint8_t>& b, uint8_t which) {
  constexpr size_t kHeader = 1024, kEntry = 40;
  if (b.size() < kHeader) return;
  const uint64_t count = loadAt<uint64_t>(b, 144), indexOffset = loadAt<uint64_t>(b, 152);
  const bool indexFits = indexOffset <= b.size() && count <= (b.size() - indexOffset) / kEntry;
  if ((which & kFixPayloads) && indexFits) {
    for (uint64_t i = 0; i < count; ++i) {
      const size_t e = static_cast<size_t>(indexOffset + i * kEntry);
      const uint64_t offset = loadAt<uint64_t>(b, e);
      uint64_t bytes = 4;  // version 1: the NCP's float32 control points
      for (int a = 0; a < 3; ++a) bytes *= loadAt<uint16_t>(b, e + 8 + 2 * a);
      if (loadAt<uint32_t>(b, 8) >= 2)
        bytes = loadAt<uint32_t>(b, e + 36);  // version 2: stored bytes
      if (offset <= b.size() && bytes <= b.size() - offset)
        storeAt<uint32_t>(b, e + 32, afam::crc32(b.data() + offset, bytes));
    }
  }
  if ((which & kFixIndex) && indexFits)
    storeAt<uint32_t>(b, 140, afam::crc32(b.data() + indexOffset, count * kEntry));
  if (which & kFixHeader) storeAt<uint32_t>(b, 1020, afam::crc32(b.data(), 1020));
}

}  // namespace afam_fuzz
