// SPDX-License-Identifier: BSD-3-Clause
// Host-only batched evaluation of one micro-model at many points (value, optionally gradient).
// The single-point evaluateModel (evaluate.hpp) stays the reference shared with the device; this
// is its throughput variant for the host, bitwise equal to it point by point.
#pragma once

#include <cstddef>

#include "afam/spline/evaluate.hpp"

namespace afam {

/// Value of model `m` at the n points uvw[3i..3i+2] (parameters in [0, 1]^3, clamped) into
/// value[i]; when `gradient` is non-null, d/du, d/dv, d/dw into gradient[3i..3i+2].
/// Each result is bitwise equal to evaluateModel<gradient != nullptr>(m, u, v, w, ...) in the
/// default (no -march) build. Degree 2 on all axes (the encoder's default) takes a blocked path:
/// span and basis per axis for a block of points first, then the 3x3x3 contraction across points
/// in SIMD lanes (8 with AVX2, chosen at run time, else 4); any other degree loops over
/// evaluateModel.
void evaluateModelBatch(const ModelView& m, const float* uvw, std::size_t n, float* value,
                        float* gradient);

namespace detail {
/// SIMD width evaluateModelBatch uses on this CPU: 8 (x86-64 with AVX2) or 4.
int batchLanes();
/// evaluateModelBatch with the width forced (4, or 8 where batchLanes() is 8), for tests.
void evaluateModelBatchLanes(int lanes, const ModelView& m, const float* uvw, std::size_t n,
                             float* value, float* gradient);
}  // namespace detail

}  // namespace afam
