// SPDX-License-Identifier: BSD-3-Clause
// Lanes frames: an entropy stage for byte streams that a GPU decodes as fast as a CPU core decodes
// zstd. Order-0 rANS (Duda's asymmetric numeral systems, range variant) with up to 32 interleaved
// states ("lanes"): byte i of the stream belongs to lane i % L, and every lane reads its 16-bit
// renormalisation words from one shared stream in the order of i. A warp decodes a frame with one
// thread a lane (the words a step needs are found with a ballot and a population count); a CPU
// decodes the lanes in turn, each symbol's chain L symbols long, so that the core overlaps them.
//
// Frame bytes (little-endian; docs/FORMAT.md "Lanes frames"):
//   [0, 4)  magic "AFL1"
//   [4, 8)  u32 V, the bytes the frame decodes to
//   [8]     u8 L, the lanes, in [1, 32]
//   [9]     u8 m, the largest byte value that occurs
//   then    m + 1 frequencies as LEB128 varints (0 for a value that never occurs), summing to 4096
//   then    L u32 states, each in [2^16, 2^32)
//   then    u16 words to the frame's end
// Decoding byte i (lane l = i % L, state x): slot = x mod 4096; the byte s is the one whose
// cumulative range [c_s, c_s + f_s) holds slot; x = f_s * (x >> 12) + slot - c_s; then, when
// x < 2^16, x = (x << 16) | the next word. A valid frame ends with every word read and every
// state back at 2^16 (the encoder's start), which is checked.
//
// Everything the decoder computes is in this header, host-device (AFAM_HD), so the CPU decoder
// (lanes_coder.cpp) and the CUDA decoder run the same steps.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "afam/base/host_device.hpp"

namespace afam::lanes {

constexpr uint32_t kMagic = 0x314C4641u;  // "AFL1" read as a little-endian u32
constexpr int kScaleBits = 12;
constexpr uint32_t kScale = 1u << kScaleBits;  // frequencies sum to this
constexpr uint32_t kLow = 1u << 16;            // states live in [kLow, 2^32)
constexpr int kMaxLanes = 32;
constexpr size_t kFixedHeaderBytes = 10;  // magic, V, L, m

/// A decoding table entry for one slot of [0, 4096): the byte, its frequency less one and the
/// slot's distance from the byte's cumulative start, packed in 32 bits.
AFAM_HD uint32_t packSlot(uint32_t symbol, uint32_t frequency, uint32_t bias) {
  return symbol | (bias << 8) | ((frequency - 1u) << 20);
}
AFAM_HD uint32_t slotSymbol(uint32_t e) { return e & 0xffu; }

/// One decoding step of a lane: the byte of state x, and x moved past it (before renormalising).
AFAM_HD uint32_t decodeStep(uint32_t& x, const uint32_t* table) {
  const uint32_t e = table[x & (kScale - 1u)];
  x = ((e >> 20) + 1u) * (x >> kScaleBits) + ((e >> 8) & 0xfffu);
  return slotSymbol(e);
}

AFAM_HD uint32_t readU32(const uint8_t* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}
AFAM_HD uint32_t readU16(const uint8_t* p) { return uint32_t(p[0]) | uint32_t(p[1]) << 8; }

/// What a frame's header says, and where its parts lie (offsets from the frame's first byte).
struct FrameLayout {
  uint32_t symbols = 0;         ///< V
  int lanes = 0;                ///< L
  size_t statesAt = 0;          ///< first state
  size_t wordsAt = 0;           ///< first word
  uint32_t words = 0;           ///< words in the frame
  const char* error = nullptr;  ///< why the frame is not one (nullptr: it is)
};

/// Reads a frame's header and frequencies into `frequency` (256 entries, zero past m), checking
/// that they describe a frame of `bytes` bytes. Host-device: a GPU thread parses its own frame.
AFAM_HD FrameLayout parseFrame(const uint8_t* frame, size_t bytes, uint32_t* frequency) {
  FrameLayout f;
  if (bytes < kFixedHeaderBytes || readU32(frame) != kMagic) {
    f.error = "is not a lanes frame";
    return f;
  }
  f.symbols = readU32(frame + 4);
  f.lanes = frame[8];
  const int m = frame[9];
  if (f.lanes < 1 || f.lanes > kMaxLanes) {
    f.error = "names an invalid lane count";
    return f;
  }
  size_t at = kFixedHeaderBytes;
  uint32_t sum = 0;
  for (int s = 0; s < 256; ++s) frequency[s] = 0;
  for (int s = 0; s <= m; ++s) {
    uint32_t v = 0;
    for (int shift = 0;; shift += 7) {
      if (at >= bytes || shift > 14) {
        f.error = "has a damaged frequency table";
        return f;
      }
      const uint32_t b = frame[at++];
      v |= (b & 0x7fu) << shift;
      if (b < 0x80u) break;
    }
    if (v > kScale) {
      f.error = "has a damaged frequency table";
      return f;
    }
    frequency[s] = v;
    sum += v;
  }
  if (sum != kScale) {
    f.error = "has frequencies that do not sum to 4096";
    return f;
  }
  f.statesAt = at;
  f.wordsAt = at + 4 * size_t(f.lanes);
  if (f.wordsAt > bytes || (bytes - f.wordsAt) % 2 != 0) {
    f.error = "is truncated";
    return f;
  }
  f.words = uint32_t((bytes - f.wordsAt) / 2);
  return f;
}

/// Fills the 4096-slot decoding table from the frequencies (parseFrame's).
AFAM_HD void buildTable(const uint32_t* frequency, uint32_t* table) {
  uint32_t cum = 0;
  for (uint32_t s = 0; s < 256; ++s) {
    for (uint32_t k = 0; k < frequency[s]; ++k) table[cum + k] = packSlot(s, frequency[s], k);
    cum += frequency[s];
  }
}

/// Appends a lanes frame of `bytes` to out.
void appendFrame(const std::vector<uint8_t>& bytes, std::vector<uint8_t>& out);

/// The lanes a frame of V bytes is coded with: 32 once there are 64 bytes a lane.
int lanesFor(size_t symbols);

/// Decodes a frame of `bytes` bytes into out (capacity at least the frame's V). Returns V; throws
/// nothing: on a damaged frame returns -1 and sets *error to what is wrong. Frames of 32 lanes go
/// through the CPU's vector path where it has one (AVX2; `vectorPath` false: never, for tests
/// that compare the two).
int64_t decodeFrame(const uint8_t* frame, size_t bytes, uint8_t* out, size_t capacity,
                    const char** error, bool vectorPath = true);

/// V of a frame (its bytes 4-8), 0 when the frame is too short to say.
inline uint32_t frameSymbols(const uint8_t* frame, size_t bytes) {
  return bytes >= kFixedHeaderBytes ? readU32(frame + 4) : 0;
}

/// Whether [frame, frame + bytes) starts like a lanes frame.
inline bool isLanesFrame(const uint8_t* frame, size_t bytes) {
  return bytes >= kFixedHeaderBytes && readU32(frame) == kMagic;
}

}  // namespace afam::lanes
