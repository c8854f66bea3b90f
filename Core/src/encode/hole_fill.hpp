// SPDX-License-Identifier: BSD-3-Clause
// Values for the missing samples of a block (private to Core's encoder): a smooth extension of
// the valid samples into the holes, so that a spline fitted to the whole block spends nothing on an
// edge at the mask's boundary and does not ring there. The values are never stored as data: the
// bound is judged on the valid samples alone and readers return NaN at missing samples.
#pragma once

#include <cstdint>
#include <vector>

#include "afam/format/partition.hpp"

namespace afam {

/// Fills the missing samples (bit clear in `valid`, block_mask.hpp's words) of an n0 x n1 x n2
/// block in place: layer by layer outwards from the valid samples, each sample the mean of its
/// face neighbours already known, then smoothed by sweeps of the mean of its face neighbours (a
/// discrete harmonic extension, the valid samples held). At least one sample must be valid.
void fillMissing(float* samples, Int3 n, const std::vector<uint32_t>& valid);

}  // namespace afam
