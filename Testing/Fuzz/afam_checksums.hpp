// SPDX-License-Identifier: BSD-3-Clause
// Recomputes the checksums of a (possibly mutated) .afam image in place, so that mutations reach
// the code behind the checks (index validation, payload reads, decoding) instead of stopping at
// "checksum mismatch". Knows the layouts of docs/FORMAT.md: header CRC at byte 1020 over [0, 1020),
// version at 8, index CRC at 140, entry count at 144, index offset at 152, 40-byte entries with the
// payload offset at +0, NCP (3 x uint16) at +8, the payload CRC at +32 and (version 2) the stored
// payload bytes at +36; version 1 payloads are the NCP's float32 control points; version 3's commit
// slots at 1024 and 1088 and the step table they point to.
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

/// Version 3 (a run of steps): each commit slot's CRC, the step table's (of the slot with the
/// larger generation), each step's index CRC in its row and each of its payloads' CRC.
inline void fixRunChecksums(std::vector<uint8_t>& b, uint8_t which) {
  constexpr size_t kSlots = 1024, kSlot = 64, kEntry = 40, kRow = 32;
  if (b.size() < kSlots + 2 * kSlot) return;
  if (which & kFixIndex)
    for (size_t s = kSlots; s < kSlots + 2 * kSlot; s += kSlot)
      storeAt<uint32_t>(b, s + 60, afam::crc32(b.data() + s, 60));
  const size_t slot =
      loadAt<uint64_t>(b, kSlots) >= loadAt<uint64_t>(b, kSlots + kSlot) ? kSlots : kSlots + kSlot;
  const uint64_t steps = loadAt<uint64_t>(b, slot + 8), table = loadAt<uint64_t>(b, slot + 16);
  const uint64_t count = loadAt<uint64_t>(b, 144);
  if (table > b.size() || steps > (b.size() - table) / kRow ||
      b.size() - table - steps * kRow < 4 || count > b.size() / kEntry)
    return;
  for (uint64_t r = 0; r < steps; ++r) {
    const size_t row = size_t(table + r * kRow);
    const uint64_t index = loadAt<uint64_t>(b, row + 8);
    if (index > b.size() || count > (b.size() - index) / kEntry) continue;
    if (which & kFixPayloads)
      for (uint64_t i = 0; i < count; ++i) {
        const size_t e = size_t(index + i * kEntry);
        const uint64_t offset = loadAt<uint64_t>(b, e), bytes = loadAt<uint32_t>(b, e + 36);
        if (offset <= b.size() && bytes <= b.size() - offset)
          storeAt<uint32_t>(b, e + 32, afam::crc32(b.data() + offset, bytes));
      }
    if (which & kFixIndex)
      storeAt<uint32_t>(b, row + 16, afam::crc32(b.data() + index, count * kEntry));
  }
  if (which & kFixIndex)
    storeAt<uint32_t>(b, size_t(table + steps * kRow), afam::crc32(b.data() + table, steps * kRow));
}

inline void fixAfamChecksums(std::vector<uint8_t>& b, uint8_t which) {
  constexpr size_t kHeader = 1024, kEntry = 40;
  if (b.size() < kHeader) return;
  if (loadAt<uint32_t>(b, 8) == 3) {
    fixRunChecksums(b, which);
    if (which & kFixHeader) storeAt<uint32_t>(b, 1020, afam::crc32(b.data(), 1020));
    return;
  }
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
