// SPDX-License-Identifier: BSD-3-Clause
#include "afam/format/block_mask.hpp"

#include <cmath>

#include <cstring>
#include <string>

#include "afam/base/errors.hpp"

namespace afam {

namespace {

// The mask is coded bit by bit in raster order with an adaptive binary range coder whose
// probability is chosen by the eight neighbours already known (a context model, as JBIG codes
// bilevel images): inside or outside a smooth hole the neighbours agree and a bit costs a small
// fraction of a bit; along the hole's boundary the context still predicts most bits.
constexpr int kProbabilityBits = 15;
constexpr uint32_t kProbabilityOne = 1u << kProbabilityBits;
constexpr int kAdaptShift = 4;
constexpr uint32_t kTopValue = 1u << 24;
constexpr int kContexts = 256;

bool bitOf(const std::vector<uint32_t>& w, int64_t i) {
  return ((w[size_t(i >> 5)] >> (i & 31)) & 1u) != 0;
}
void setBit(std::vector<uint32_t>& w, int64_t i) { w[size_t(i >> 5)] |= 1u << (i & 31); }

/// The context of sample (x, y, z): its known neighbours W, N, NW, NE in its plane and B, BW, BE,
/// BN in the plane below, one bit each (0 outside the block).
int contextOf(const std::vector<uint32_t>& w, Int3 n, int x, int y, int z) {
  const int64_t sy = n[0], sz = int64_t(n[0]) * n[1];
  const int64_t i = (int64_t(z) * n[1] + y) * n[0] + x;
  const bool west = x > 0, east = x + 1 < n[0], north = y > 0, below = z > 0;
  int c = 0;
  c |= (west && bitOf(w, i - 1)) << 0;
  c |= (north && bitOf(w, i - sy)) << 1;
  c |= (north && west && bitOf(w, i - sy - 1)) << 2;
  c |= (north && east && bitOf(w, i - sy + 1)) << 3;
  c |= (below && bitOf(w, i - sz)) << 4;
  c |= (below && west && bitOf(w, i - sz - 1)) << 5;
  c |= (below && east && bitOf(w, i - sz + 1)) << 6;
  c |= (below && north && bitOf(w, i - sz - sy)) << 7;
  return c;
}

void adapt(uint16_t& p, bool bit) {
  if (bit)
    p = uint16_t(p - (p >> kAdaptShift));
  else
    p = uint16_t(p + ((kProbabilityOne - p) >> kAdaptShift));
}

class RangeEncoder {
 public:
  void encode(uint16_t& p, bool bit) {
    const uint32_t bound = (range_ >> kProbabilityBits) * p;
    if (!bit) {
      range_ = bound;
    } else {
      low_ += bound;
      range_ -= bound;
    }
    adapt(p, bit);
    while (range_ < kTopValue) {
      range_ <<= 8;
      shiftLow();
    }
  }
  std::vector<uint8_t> finish() {
    for (int k = 0; k < 5; ++k) shiftLow();
    return std::move(out_);
  }

 private:
  void shiftLow() {
    if (uint32_t(low_) < 0xFF000000u || (low_ >> 32) != 0) {
      const uint8_t carry = uint8_t(low_ >> 32);
      if (started_) out_.push_back(uint8_t(cache_ + carry));
      started_ = true;
      for (; pending_ > 0; --pending_) out_.push_back(uint8_t(0xFF + carry));
      cache_ = uint8_t(low_ >> 24);
    } else {
      ++pending_;
    }
    low_ = (low_ & 0x00FFFFFFu) << 8;
  }
  uint64_t low_ = 0;
  uint32_t range_ = 0xFFFFFFFFu;
  uint8_t cache_ = 0;
  bool started_ = false;
  uint64_t pending_ = 0;
  std::vector<uint8_t> out_;
};

class RangeDecoder {
 public:
  RangeDecoder(const uint8_t* data, size_t bytes) : data_(data), bytes_(bytes) {
    for (int k = 0; k < 4; ++k) code_ = (code_ << 8) | next();
  }
  bool decode(uint16_t& p) {
    const uint32_t bound = (range_ >> kProbabilityBits) * p;
    bool bit;
    if (code_ < bound) {
      range_ = bound;
      bit = false;
    } else {
      code_ -= bound;
      range_ -= bound;
      bit = true;
    }
    adapt(p, bit);
    while (range_ < kTopValue) {
      range_ <<= 8;
      code_ = (code_ << 8) | next();
    }
    return bit;
  }
  /// Whether decoding read the data to its end and no further (a coded mask is exactly the bytes
  /// its encoder wrote).
  bool consumedExactly() const { return pos_ == bytes_; }

 private:
  uint32_t next() { return pos_ < bytes_ ? data_[pos_++] : (++pos_, 0u); }
  const uint8_t* data_;
  size_t bytes_, pos_ = 0;
  uint32_t code_ = 0, range_ = 0xFFFFFFFFu;
};

int64_t sampleCount(Int3 n) { return int64_t(n[0]) * n[1] * n[2]; }

/// Starting probabilities of a 0 bit per context, before any bit adapts them: the more of the
/// eight neighbours are set, the likelier the bit is (a block codes few bits, too few to learn
/// 256 contexts from an even start).
std::vector<uint16_t> priorProbabilities() {
  std::vector<uint16_t> p(kContexts);
  for (int c = 0; c < kContexts; ++c) {
    const double set = (__builtin_popcount(unsigned(c)) + 0.05) / 8.1;
    p[size_t(c)] = uint16_t(std::lround((1.0 - set) * double(kProbabilityOne)));
  }
  return p;
}

}  // namespace

std::vector<uint32_t> maskOfValid(const float* samples, int64_t count) {
  std::vector<uint32_t> w(size_t(maskWordCount(count)), 0u);
  for (int64_t i = 0; i < count; ++i)
    if (!std::isnan(samples[i])) setBit(w, i);
  return w;
}

int64_t validCount(const std::vector<uint32_t>& words) {
  int64_t c = 0;
  for (uint32_t w : words) c += __builtin_popcount(w);
  return c;
}

std::vector<uint8_t> encodeMask(const std::vector<uint32_t>& words, Int3 n) {
  std::vector<uint16_t> p = priorProbabilities();
  RangeEncoder coder;
  int64_t i = 0;
  for (int z = 0; z < n[2]; ++z)
    for (int y = 0; y < n[1]; ++y)
      for (int x = 0; x < n[0]; ++x, ++i)
        coder.encode(p[size_t(contextOf(words, n, x, y, z))], bitOf(words, i));
  return coder.finish();
}

void decodeMask(const uint8_t* data, size_t bytes, Int3 n, float* out, const char* where) {
  const int64_t count = sampleCount(n);
  std::vector<uint32_t> words(size_t(maskWordCount(count)), 0u);
  std::vector<uint16_t> p = priorProbabilities();
  RangeDecoder coder(data, bytes);
  int64_t i = 0;
  for (int z = 0; z < n[2]; ++z)
    for (int y = 0; y < n[1]; ++y)
      for (int x = 0; x < n[0]; ++x, ++i)
        if (coder.decode(p[size_t(contextOf(words, n, x, y, z))])) setBit(words, i);
  if (!coder.consumedExactly())
    throw FormatError(std::string(where) + ": mask of " + std::to_string(bytes) +
                      " bytes does not code " + std::to_string(count) + " samples");
  std::memcpy(out, words.data(), words.size() * 4);
}

size_t maskSectionBytes(size_t codedMaskBytes) { return (4 + codedMaskBytes + 3) / 4 * 4; }

size_t readMaskSection(const uint8_t* stored, size_t bytes, Int3 n, float* words,
                       const char* where) {
  uint32_t coded = 0;
  if (bytes >= 4) std::memcpy(&coded, stored, 4);
  if (bytes < 4 || coded == 0 || maskSectionBytes(coded) > bytes)
    throw FormatError(std::string(where) + ": masked payload's mask (" + std::to_string(coded) +
                      " bytes) does not fit its " + std::to_string(bytes) + " bytes");
  decodeMask(stored + 4, coded, n, words, where);
  return maskSectionBytes(coded);
}

}  // namespace afam
