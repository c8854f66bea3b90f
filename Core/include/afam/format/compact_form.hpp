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

}  // namespace afam
