// SPDX-License-Identifier: BSD-3-Clause
// Error-bounded coding of one micro-model's values (control points of a spline, or the samples of a
// block stored as a degree-1 spline): uniform quantization to integers Q = round(v / step), a
// lossless predictor over the integer lattice, and zstd over the prediction residuals.
//
// Why the bound carries over to the model: B-spline basis functions are non-negative and sum to
// one, so moving every control point by at most step/2 moves the model by at most step/2
// everywhere (the maximum error the quantization can add). The encoder still measures the coded
// model on the block's samples before accepting it.
//
// Predictors (on the integer lattice, exact integer arithmetic, so encoder and decoder agree bit
// for bit on every compiler):
//   Lorenzo: Q(x,y,z) predicted from its seven lower neighbours of the unit cube (missing = 0);
//            suits the small, smooth lattices of control points.
//   Interpolation: a multi-resolution scheme. The points whose coordinates are all multiples of
//            S (the largest power of two below the longest axis) are Lorenzo-coded on their own
//            lattice; then for s = S/2, ..., 1 the points at odd multiples of s are predicted along
//            x, then y, then z from the known points at +-s (cubic (-a + 9b + 9c - d) / 16 where
//            +-3s exist, linear (b + c) / 2 where +-s exist, else the one neighbour). Suits samples.
// Residuals are zigzag varints (1 byte when |r| < 64) compressed by zstd.
//
// Coded payload bytes: [0, 8) f64 step; [8] u8 predictor (0 Lorenzo, 1 interpolation);
// [9, end) one zstd frame holding the varints, one per value, in the predictor's visiting order.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "afam/partition.hpp"

namespace afam {

enum class Predictor : uint8_t { Lorenzo = 0, Interpolation = 1 };

/// Bytes before the zstd frame in a coded payload.
constexpr size_t kCodedHeaderBytes = 9;

/// Largest |v / step| the integer lattice takes (exact int64 arithmetic in the predictors).
constexpr double kMaxQuantized = 1125899906842624.0;  // 2^50

/// Quantizes `values` (n[0] * n[1] * n[2], x fastest) with `step` and codes them. Returns false
/// (and leaves `out` empty) when a value is too large for the lattice (|v / step| > 2^50).
/// `reconstructed` receives the decoded values (float), as decodeValues would produce them.
bool encodeValues(const float* values, Int3 n, double step, Predictor predictor, int zstdLevel,
                  std::vector<uint8_t>& out, std::vector<float>& reconstructed);

/// Decodes a coded payload of n[0] * n[1] * n[2] values into out. Throws FormatError (with
/// `where` in the message) when the bytes are not a valid coded payload of that size.
void decodeValues(const uint8_t* data, size_t bytes, Int3 n, float* out, const char* where);

}  // namespace afam
