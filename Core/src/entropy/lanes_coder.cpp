// SPDX-License-Identifier: BSD-3-Clause
#include "afam/entropy/lanes_coder.hpp"

#include <algorithm>
#include <array>

#include "lanes_simd.hpp"

namespace afam::lanes {

namespace {

/// Frequencies summing to kScale, at least 1 for every byte that occurs, proportional to the
/// counts otherwise; the rounding goes to (or comes from) the most frequent bytes,
/// deterministically.
std::array<uint32_t, 256> normalise(const std::array<uint64_t, 256>& count, uint64_t total) {
  std::array<uint32_t, 256> f{};
  if (total == 0) {
    f[0] = kScale;  // an empty frame still carries a valid table
    return f;
  }
  int64_t sum = 0;
  for (int s = 0; s < 256; ++s)
    if (count[s]) {
      f[s] = uint32_t(std::max<uint64_t>(1, count[s] * kScale / total));
      sum += f[s];
    }
  while (sum != kScale) {
    const auto largest = std::max_element(f.begin(), f.end());  // first of the largest
    if (sum < kScale) {
      *largest += uint32_t(kScale - sum);
      sum = kScale;
    } else {
      const int64_t take = std::min<int64_t>(*largest - 1, sum - kScale);
      *largest -= uint32_t(take);
      sum -= take;
    }
  }
  return f;
}

void putU32(uint32_t v, std::vector<uint8_t>& out) {
  for (int b = 0; b < 4; ++b) out.push_back(uint8_t(v >> (8 * b)));
}

}  // namespace

int lanesFor(size_t symbols) { return int(std::clamp<size_t>(symbols / 64, 1, kMaxLanes)); }

void appendFrame(const std::vector<uint8_t>& bytes, std::vector<uint8_t>& out) {
  const size_t V = bytes.size();
  const int L = lanesFor(V);
  std::array<uint64_t, 256> count{};
  for (const uint8_t b : bytes) ++count[b];
  const std::array<uint32_t, 256> f = normalise(count, V);
  std::array<uint32_t, 256> cum{};
  for (int s = 1; s < 256; ++s) cum[s] = cum[s - 1] + f[s - 1];
  int m = 255;
  while (m > 0 && f[m] == 0) --m;

  // Encode backwards: byte i's renormalisation word, written before its state update, is read
  // by the decoder right after it decodes byte i, so the words come out in decoding order once
  // reversed.
  std::array<uint32_t, kMaxLanes> state;
  state.fill(kLow);
  std::vector<uint16_t> words;
  words.reserve(V / 2 + 16);
  for (size_t i = V; i-- > 0;) {
    uint32_t& x = state[i % size_t(L)];
    const uint32_t fs = f[bytes[i]];
    if (uint64_t(x) >= (uint64_t(fs) << 20)) {  // ((kLow >> kScaleBits) << 16) * fs
      words.push_back(uint16_t(x));
      x >>= 16;
    }
    x = ((x / fs) << kScaleBits) + x % fs + cum[bytes[i]];
  }

  putU32(kMagic, out);
  putU32(uint32_t(V), out);
  out.push_back(uint8_t(L));
  out.push_back(uint8_t(m));
  for (int s = 0; s <= m; ++s)
    for (uint32_t v = f[s];; v >>= 7) {
      out.push_back(uint8_t(v >= 0x80 ? (v & 0x7f) | 0x80 : v));
      if (v < 0x80) break;
    }
  for (int l = 0; l < L; ++l) putU32(state[size_t(l)], out);
  for (size_t w = words.size(); w-- > 0;) {
    out.push_back(uint8_t(words[w]));
    out.push_back(uint8_t(words[w] >> 8));
  }
}

int64_t decodeFrame(const uint8_t* frame, size_t bytes, uint8_t* out, size_t capacity,
                    const char** error, bool vectorPath) {
  uint32_t frequency[256];
  const FrameLayout f = parseFrame(frame, bytes, frequency);
  if (f.error) {
    *error = f.error;
    return -1;
  }
  if (f.symbols > capacity) {
    *error = "decodes to more bytes than its block holds";
    return -1;
  }
  uint32_t table[kScale];  // 16 KB on the stack (a thread_local would cost a TLS lookup a slot)
  buildTable(frequency, table);
  const int L = f.lanes;
  uint32_t x[kMaxLanes];
  for (int l = 0; l < L; ++l) {
    x[l] = readU32(frame + f.statesAt + 4 * size_t(l));
    if (x[l] < kLow) {
      *error = "has an invalid state";
      return -1;
    }
  }
  const uint8_t* words = frame + f.wordsAt;
  uint32_t pos = 0;
  const size_t V = f.symbols;
  size_t i = 0;
  if (L == kMaxLanes && vectorPath && vectorPathAvailable())
    decodeSteps32(x, table, words, f.words, pos, out, V, i);
  // Whole steps while the words cannot run out (a step reads at most L): no bounds test, the
  // renormalisation without a branch.
  while (i + size_t(L) <= V && pos + uint32_t(L) <= f.words) {
    for (int l = 0; l < L; ++l) {
      out[i + size_t(l)] = uint8_t(decodeStep(x[l], table));
      // Arithmetic, not a select: compilers turn a select into a branch that mispredicts on
      // about a fifth of the bytes (measured: half the decoding time).
      const uint32_t need = x[l] < kLow;
      const uint32_t w = readU16(words + 2 * size_t(pos));
      x[l] = (x[l] << (need << 4)) | (w & (0u - need));
      pos += need;
    }
    i += size_t(L);
  }
  for (; i < V; ++i) {  // the rest, checked
    uint32_t& s = x[i % size_t(L)];
    out[i] = uint8_t(decodeStep(s, table));
    if (s < kLow) {
      if (pos >= f.words) {
        *error = "is truncated";
        return -1;
      }
      s = (s << 16) | readU16(words + 2 * size_t(pos++));
    }
  }
  bool ends = pos == f.words;
  for (int l = 0; l < L; ++l) ends = ends && x[l] == kLow;
  if (!ends) {
    *error = "is damaged (its states do not end where the encoder began)";
    return -1;
  }
  return int64_t(V);
}

}  // namespace afam::lanes
