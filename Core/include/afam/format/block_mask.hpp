// SPDX-License-Identifier: BSD-3-Clause
// The mask of valid samples of one micro-block (format version 3, issue 30: missing values).
//
// In memory (what AfamFile::readPayload gives for a masked entry, what caches hold and the casters
// read): after the model's prod(ncp) float32 control points come maskWordCount(samples) 32-bit
// words, stored in the same float array bit for bit (never read as floats). Sample i of the block's
// n0 x n1 x n2 sample grid (x fastest, Partition::extent's samples of its level) is valid when bit
// (i % 32) of word (i / 32) is set; bits past the last sample are 0. A valid sample has a value
// within the file's bound; a missing one has none (readers return NaN there).
//
// On disk the words are coded (block_mask.cpp; docs/FORMAT.md "Masks").
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "afam/base/host_device.hpp"
#include "afam/format/partition.hpp"

namespace afam {

/// 32-bit mask words of a block of `samples` samples per axis.
AFAM_HD int64_t maskWordCount(int64_t sampleCount) { return (sampleCount + 31) / 32; }

/// Whether sample i is valid, from mask words read out of a float array (bit-cast, not converted).
AFAM_HD bool maskBit(const float* words, int64_t i) {
  const float w = words[i >> 5];
  uint32_t bits;
#if defined(__CUDA_ARCH__)  // device code (nvcc's host pass takes memcpy)
  bits = __float_as_uint(w);
#else
  std::memcpy(&bits, &w, sizeof bits);
#endif
  return ((bits >> (i & 31)) & 1u) != 0;
}

/// Mask words of samples (count of them): bit set where the sample is not NaN.
std::vector<uint32_t> maskOfValid(const float* samples, int64_t count);

/// Number of valid samples of a mask.
int64_t validCount(const std::vector<uint32_t>& words);

/// The mask of a block of n samples per axis coded for a file: its bits in raster order through an
/// adaptive binary range coder whose probabilities are chosen by the eight neighbours already
/// coded (docs/FORMAT.md "Masks" gives the exact rules).
std::vector<uint8_t> encodeMask(const std::vector<uint32_t>& words, Int3 n);

/// Decodes a coded mask of a block of n samples per axis into maskWordCount words, written as bit
/// patterns into `out` (a float array, as in memory above). Throws FormatError naming `where` when
/// the bytes are not a mask of that size, or set a bit past the last sample.
void decodeMask(const uint8_t* data, size_t bytes, Int3 n, float* out, const char* where);

/// Bytes of the mask section a masked payload starts with: a u32 of the coded mask's length, the
/// coded mask, zeros to a multiple of 4 (the model's payload after it stays float-aligned).
size_t maskSectionBytes(size_t codedMaskBytes);

/// The mask section of a masked payload: where the model's own payload starts (the section's
/// length). Throws FormatError naming `where` when the section does not fit in `bytes`.
size_t readMaskSection(const uint8_t* stored, size_t bytes, Int3 n, float* words,
                       const char* where);

}  // namespace afam
