// SPDX-License-Identifier: BSD-3-Clause
// The compact form of a decoded model (what a cache may keep instead of its floats).
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

namespace afam {

/// A model kept compact: the values of an integer-coded payload are (base + k) * step for k in
/// [lo, hi] (a rounded interpolant's points k * q, rounded_points.hpp), so when hi - lo < 65,536
/// they can be kept as a table of those floats and one code a value (width bytes: 1 for at most 256
/// distinct k, else 2) instead of float32 values: in a float array, the table's `table` floats,
/// then the codes (k - lo) packed, the last float padded with zeros. Reading table[code] gives the
/// floats decodeValues gives, bit for bit. width 0: plain floats.
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

/// The compact form of `count` values given by their integer codes k (value valueOf(k), the float
/// the decoder gives for k), into out, when the codes span at most 65,536 integers and the form
/// takes at most maxShare of the floats' bytes; otherwise width 0 and out untouched.
template <typename Code, typename ValueOf>
CompactForm packCompact(const Code* k, uint64_t count, double maxShare, ValueOf valueOf,
                        std::vector<float>& out) {
  if (count == 0) return CompactForm{};
  const auto [lo, hi] = std::minmax_element(k, k + count);
  const uint64_t span = uint64_t(int64_t(*hi) - int64_t(*lo)) + 1;
  CompactForm form;
  form.width = span <= 256 ? 1 : span <= 65536 ? 2 : 0;
  const uint64_t floats = span + (count * uint64_t(form.width) + 3) / 4;
  if (form.width == 0 || double(floats) > maxShare * double(count)) return CompactForm{};
  form.table = uint32_t(span);
  const int64_t first = int64_t(*lo);
  out.assign(floats, 0.f);
  for (uint64_t j = 0; j < span; ++j) out[j] = valueOf(first + int64_t(j));
  auto* codes = reinterpret_cast<unsigned char*>(out.data() + span);
  for (uint64_t i = 0; i < count; ++i) {
    const auto c = uint16_t(int64_t(k[i]) - first);  // little-endian, as expandCompact reads
    codes[i * uint64_t(form.width)] = uint8_t(c & 0xff);
    if (form.width == 2) codes[i * 2 + 1] = uint8_t(c >> 8);
  }
  return form;
}

}  // namespace afam
