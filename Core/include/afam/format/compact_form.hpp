// SPDX-License-Identifier: BSD-3-Clause
// The compact form of a decoded model (what a cache may keep instead of its floats).
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

#include "afam/base/host_device.hpp"

namespace afam {

/// Most distinct codes a compact form holds (2-byte codes).
constexpr uint64_t kMaxCompactSpan = 65536;

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

/// Floats a compact form of `count` values takes: its table of `table` floats, then `width`-byte
/// codes, the last float padded (host and device).
AFAM_HD uint64_t compactFloats(uint64_t table, uint64_t width, uint64_t count) {
  return table + (count * width + 3) / 4;
}

namespace detail {
template <typename Code>
void expandCodes(const float* table, const unsigned char* bytes, uint64_t count, float* out) {
  for (uint64_t i = 0; i < count; ++i) {
    Code code;
    std::memcpy(&code, bytes + i * sizeof(Code), sizeof(Code));  // little-endian, as written
    out[i] = table[code];
  }
}

template <typename Code, typename K>
void writeCodes(const K* k, uint64_t count, int64_t first, unsigned char* bytes) {
  for (uint64_t i = 0; i < count; ++i) {
    const auto code = Code(int64_t(k[i]) - first);
    std::memcpy(bytes + i * sizeof(Code), &code, sizeof(Code));
  }
}
}  // namespace detail

/// The `count` values of a model in compact form `f` (its floats at `data`) as float32, into out.
inline void expandCompact(const float* data, CompactForm f, uint64_t count, float* out) {
  const auto* codes = reinterpret_cast<const unsigned char*>(data + f.table);
  if (f.width == 1)
    detail::expandCodes<uint8_t>(data, codes, count, out);
  else
    detail::expandCodes<uint16_t>(data, codes, count, out);
}

/// The compact form of `count` values given by their integer codes k (value valueOf(k), the float
/// the decoder gives for k), into out, when the codes span at most 65,536 integers and the form
/// takes at most maxShare of the floats' bytes; otherwise width 0 and out untouched.
template <typename Code, typename ValueOf>
CompactForm packCompact(const Code* k, uint64_t count, double maxShare, ValueOf valueOf,
                        std::vector<float>& out) {
  if (count == 0) return CompactForm{};
  Code lo = k[0], hi = k[0];
  for (uint64_t i = 1; i < count; ++i) {  // values, not positions: this loop vectorizes
    lo = std::min(lo, k[i]);
    hi = std::max(hi, k[i]);
  }
  const uint64_t span = uint64_t(int64_t(hi) - int64_t(lo)) + 1;
  CompactForm form;
  form.width = span <= 256 ? 1 : span <= kMaxCompactSpan ? 2 : 0;
  const uint64_t floats = compactFloats(span, uint64_t(form.width), count);
  if (form.width == 0 || double(floats) > maxShare * double(count)) return CompactForm{};
  form.table = uint32_t(span);
  const int64_t first = int64_t(lo);
  out.resize(floats);
  out.back() = 0.f;  // the last float's padding
  for (uint64_t j = 0; j < span; ++j) out[j] = valueOf(first + int64_t(j));
  auto* codes = reinterpret_cast<unsigned char*>(out.data() + span);
  if (form.width == 1)
    detail::writeCodes<uint8_t>(k, count, first, codes);
  else
    detail::writeCodes<uint16_t>(k, count, first, codes);
  return form;
}

}  // namespace afam
