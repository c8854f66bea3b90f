// SPDX-License-Identifier: BSD-3-Clause
// What both forms of the block codec (block_codec.cpp: double forms and the public functions;
// integer_codec.cpp: integer forms) share: the entropy stages (zstd contexts, lanes frames), the
// calling thread's scratch buffers, zigzag varints and the payload's error messages. Internal to
// Core/src/format.
#pragma once

#include <zstd.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/base/round_half_even.hpp"
#include "afam/base/thread_scratch.hpp"
#include "afam/entropy/lanes_coder.hpp"
#include "afam/entropy/zstd_contexts.hpp"
#include "afam/format/block_codec.hpp"
#include "afam/format/partition.hpp"
#include "afam/format/value_prediction.hpp"

namespace afam::codec {

using afam::threadCCtx;  // zstd_contexts.hpp
using afam::threadDCtx;

inline void putVarint(uint64_t u, std::vector<uint8_t>& out) {
  while (u >= 0x80) {
    out.push_back(uint8_t(u | 0x80));
    u >>= 7;
  }
  out.push_back(uint8_t(u));
}

inline uint64_t zigzag(int64_t c) { return (uint64_t(c) << 1) ^ uint64_t(c >> 63); }

using afam::kRoundExact;  // round_half_even.hpp
using afam::roundHalfEven;

/// Appends one zstd frame of `bytes` to out (after what out holds).
inline void appendZstdFrame(const std::vector<uint8_t>& bytes, int level,
                            std::vector<uint8_t>& out) {
  const size_t head = out.size();
  out.resize(head + ZSTD_compressBound(bytes.size()));
  const size_t z = ZSTD_compressCCtx(threadCCtx(), out.data() + head, out.size() - head,
                                     bytes.data(), bytes.size(), level);
  if (ZSTD_isError(z)) throw Error(std::string("zstd: ") + ZSTD_getErrorName(z));
  out.resize(head + z);
}

/// Appends the frame `coding` asks for: zstd, lanes, or (Auto) the lanes frame unless the zstd
/// frame is more than kLanesMargin smaller (keepsLanes). Returns the sizes of the frames formed.
inline FrameSizes appendEntropyFrame(const std::vector<uint8_t>& bytes, EntropyCoding coding,
                                     std::vector<uint8_t>& out) {
  const size_t head = out.size();
  FrameSizes sizes;
  if (coding.stage != EntropyStage::Lanes) {
    appendZstdFrame(bytes, coding.zstdLevel, out);
    sizes.zstd = out.size() - head;
  }
  if (coding.stage == EntropyStage::Zstd) return sizes;
  thread_local std::vector<uint8_t> frame;
  frame.clear();
  lanes::appendFrame(bytes, frame);
  sizes.lanes = frame.size();
  if (coding.stage == EntropyStage::Lanes || keepsLanes(double(sizes.lanes), double(sizes.zstd))) {
    out.resize(head);
    out.insert(out.end(), frame.begin(), frame.end());
  }
  return sizes;
}

/// The error of a payload that does not decode: "<where>: coded payload <what>".
inline FormatError badPayload(const char* where, const std::string& what) {
  return FormatError(std::string(where) + ": coded payload " + what);
}

/// Decodes the lanes frame [frame, frame + bytes) as unpackFrame does.
inline const uint8_t* unpackLanesFrame(const uint8_t* frame, size_t bytes, size_t capacity,
                                       size_t padding, const char* where, size_t& got) {
  const size_t symbols = lanes::frameSymbols(frame, bytes);
  uint8_t* out = threadScratch<uint8_t>(ScratchSlot::Frame, std::min(symbols, capacity) + padding);
  const char* error = nullptr;
  const int64_t n = lanes::decodeFrame(frame, bytes, out, capacity, &error);
  if (n < 0) throw badPayload(where, std::string("lanes frame ") + error);
  got = size_t(n);
  std::fill(out + got, out + got + padding, uint8_t(0));
  return out;
}

/// Decompresses the frame [frame, frame + bytes) (zstd, or lanes) into the calling thread's
/// scratch (ScratchSlot::Frame) with at most `capacity` bytes, and `padding` zero bytes after what
/// it holds; returns the buffer and sets `got`.
inline const uint8_t* unpackFrame(const uint8_t* frame, size_t bytes, size_t capacity,
                                  size_t padding, const char* where, size_t& got) {
  if (lanes::isLanesFrame(frame, bytes))
    return unpackLanesFrame(frame, bytes, capacity, padding, where, got);
  const unsigned long long framed = ZSTD_getFrameContentSize(frame, bytes);
  if (framed == ZSTD_CONTENTSIZE_ERROR)
    throw badPayload(where, "does not decompress (not a zstd frame)");
  if (framed != ZSTD_CONTENTSIZE_UNKNOWN && framed < capacity) capacity = size_t(framed);
  uint8_t* out = threadScratch<uint8_t>(ScratchSlot::Frame, capacity + padding);
  got = ZSTD_decompressDCtx(threadDCtx(), out, capacity, frame, bytes);
  if (ZSTD_isError(got))
    throw badPayload(where, std::string("does not decompress (") + ZSTD_getErrorName(got) + ")");
  std::fill(out + got, out + got + padding, uint8_t(0));
  return out;
}

/// lorenzo at s = 1 with the interior rows of a plane four at a time, each a point behind the one
/// before (row y + 1 at x reads row y at x and x - 1, known by then): four independent chains in
/// flight where fn's work on a point waits for the point before it (a quantization through
/// floating-point predictions). The same predictions of the same points, in another order: fn
/// must not depend on the order.
template <typename T, typename Fn>
inline void lorenzoFourRows(const Lattice& L, const T* q, Fn&& fn) {
  const int64_t nx = L.n[0], sy = L.n[0], sz = int64_t(L.n[0]) * L.n[1];
  for (int z = 0; z < L.n[2]; ++z)
    for (int y = 0; y < L.n[1];) {
      if (z == 0 || y == 0 || y + 4 > L.n[1]) {
        lorenzoRow(L, q, 1, y, z, fn);
        ++y;
        continue;
      }
      for (int64_t t = 0; t < nx + 3; ++t)
        for (int j = 0; j < 4; ++j) {
          const int64_t x = t - j;
          if (x < 0 || x >= nx) continue;
          const int64_t i = L.index(0, y + j, z) + x;
          fn(i,
             x == 0 ? lorenzoRowStart(q, i, sy, sz, true, true) : lorenzoInterior(q, i, 1, sy, sz));
        }
      y += 4;
    }
}

}  // namespace afam::codec
