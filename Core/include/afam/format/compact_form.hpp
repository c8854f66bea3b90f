// SPDX-License-Identifier: BSD-3-Clause
// The compact form of a decoded model (what a cache may keep instead of its floats).
#pragma once

#include <cstdint>

namespace afam {

/// A model kept compact: the values of an integer-coded payload are (base + k) * step for k in
/// [lo, hi], so when hi - lo < 65,536 they can be kept as a table of those floats and one code
/// a value (width bytes: 1 for at most 256 distinct k, else 2) instead of float32 values: in a
/// float array, the table's `table` floats, then the codes (k - lo) packed, the last float padded
/// with zeros. Reading table[code] gives the floats decodeValues gives, bit for bit. width 0:
/// plain floats.
struct CompactForm {
  int width = 0;
  uint32_t table = 0;
};

/// The `count` values of a model in compact form `f` (its floats at `data`) as float32, into out.
inline void expandCompact(const float* data, CompactForm f, uint64_t count, float* out) {
  const auto* codes = reinterpret_cast<const unsigned char*>(data + f.table);
  for (uint64_t i = 0; i < count; ++i) {
    uint32_t code = codes[i * uint64_t(f.width)];
    if (f.width == 2) code |= uint32_t(codes[i * 2 + 1]) << 8;  // little-endian, as written
    out[i] = data[code];
  }
}

}  // namespace afam
