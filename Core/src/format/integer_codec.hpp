// SPDX-License-Identifier: BSD-3-Clause
// The integer forms of the block codec (block_codec.hpp says what they are): quantization of each
// value on its own, the predictors on the integers, and decoding in passes without a serial chain
// (varints, then prefix sums or interpolation passes, then the conversion to float), each a loop
// the compiler vectorizes. Internal to Core/src/format; block_codec.cpp dispatches to it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "afam/base/huge_pages.hpp"
#include "afam/format/block_codec.hpp"

namespace afam::codec {

/// Quantizes every value on its own: k = round(value / step) - base, base the middle of the
/// values in steps. False when a value is not finite or some |k| >= 2^26.
bool integerQuantize(const float* values, size_t count, double step, int64_t& base,
                     HugePageVector<int32_t>& k);

/// What a reader reconstructs from k: float((base + k) * step); base + k is formed as
/// double(base) + double(k), exact as both lie below 2^53 (and vectorizable).
inline float integerValue(int64_t base, int32_t k, double step) {
  return static_cast<float>((double(base) + double(k)) * step);
}

/// out[i] = integerValue(base, k[i], step) for `count` codes (vectorised, compiled also for AVX2).
void integerValues(int64_t base, const int32_t* k, size_t count, double step, float* out);

/// The residuals of k under an integer predictor, in the predictor's visiting order. With free
/// values (block_codec.hpp's FreeValues; interpolation only), a free point whose prediction lies
/// within free.slack of its k takes the prediction as its k, and its residual is 0. `residuals`
/// holds k.size() values.
void integerResiduals(Predictor p, Int3 n, HugePageVector<int32_t>& k, int32_t* residuals,
                      FreeValues free = {});

/// Decodes an integer-form payload (data[8] names an integer predictor) into out.
void decodeInteger(const uint8_t* data, size_t bytes, Int3 n, float* out, const char* where);

/// Decodes an integer-form payload into its compact form (block_codec.hpp's CompactForm) when
/// that takes at most maxShare of the floats' bytes, else into floats (width 0).
CompactForm decodeIntegerCompact(const uint8_t* data, size_t bytes, Int3 n, double maxShare,
                                 std::vector<float>& out, const char* where);

}  // namespace afam::codec
