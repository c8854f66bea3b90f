// SPDX-License-Identifier: BSD-3-Clause
// FNV-1a over bytes: the one checksum of the predictors' side files (APPA table, LSTM weights) and
// the one fingerprint of what an APPA table was built for. Not cryptographic.
#pragma once

#include <cstddef>
#include <cstdint>

namespace afam {

/// 32-bit FNV-1a of `bytes` bytes.
inline uint32_t fnv1a32(const void* data, std::size_t bytes) {
  const auto* p = static_cast<const unsigned char*>(data);
  uint32_t h = 0x811C9DC5u;
  for (std::size_t i = 0; i < bytes; ++i) {
    h ^= p[i];
    h *= 0x01000193u;
  }
  return h;
}

/// 64-bit FNV-1a of `bytes` bytes, continuing from `h` (chain calls to hash several pieces).
inline uint64_t fnv1a64(const void* data, std::size_t bytes, uint64_t h = 0xcbf29ce484222325ull) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < bytes; ++i) {
    h ^= p[i];
    h *= 0x100000001b3ull;
  }
  return h;
}

}  // namespace afam
