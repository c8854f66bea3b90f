// SPDX-License-Identifier: BSD-3-Clause
// The CPU's vector path through lanes frames of 32 lanes (lanes_simd.cpp): AVX2, eight lanes a
// vector, four vectors a step, the same steps as decodeStep (lanes_coder.hpp). Internal to
// Core/src/entropy.
#pragma once

#include <cstddef>
#include <cstdint>

namespace afam::lanes {

/// True when this CPU runs the vector path (x86-64 with AVX2; false elsewhere).
bool vectorPathAvailable();

/// Decodes whole steps of 32 lanes (bytes i .. i + 31) while a step fits in `symbols` and 32 words
/// remain after `pos`: the states x[0..31] and i and pos advance as the scalar loop would advance
/// them. Only where vectorPathAvailable().
void decodeSteps32(uint32_t* x, const uint32_t* table, const uint8_t* words, uint32_t wordCount,
                   uint32_t& pos, uint8_t* out, size_t symbols, size_t& i);

}  // namespace afam::lanes
