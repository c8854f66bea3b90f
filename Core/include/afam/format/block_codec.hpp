// SPDX-License-Identifier: BSD-3-Clause
// Error-bounded coding of one micro-model's values (control points of a spline, or the samples of a
// block stored as a degree-1 spline), the way SZ's predictors work: every value is predicted from
// the values already reconstructed, the residual is quantized to an integer code with a uniform
// step (reconstruction = prediction + code * step, within step / 2 of the value), and zstd packs
// the codes.
//
// Why the bound carries over to the model: B-spline basis functions are non-negative and sum to
// one, so moving every control point by at most step/2 moves the model by at most step/2
// everywhere (the maximum error the quantization can add). The encoder still measures the coded
// model on the block's samples before accepting it.
//
// Two forms of each predictor (payload byte 8 names the form):
//   Integer forms (2 IntegerLorenzo, 3 IntegerInterpolation; written whenever they fit): every
//            value is first quantized on its own, k = round(value / step) - base (base the
//            values' middle in steps), and the predictors work on the integers k, exactly: a
//            reconstruction is (base + k) * step, within step / 2 of its value whatever the
//            predictor. Decoding needs no serial chain through floating-point sums: the inverse
//            of Lorenzo is a prefix sum along x, y and z, and each interpolation pass reads only
//            points known before it. They fit when every |k| < 2^26 (a spread of 2^27 steps).
//   Double forms (0 Lorenzo, 1 Interpolation; the encoder's fallback beyond that spread, and
//            every file written before the integer forms): the residual of a prediction from the
//            values already reconstructed is quantized (reconstruction = prediction + code *
//            step), in double arithmetic in one fixed order, compiled without FMA contraction, so
//            encoder and decoder reconstruct bit-identical values.
// The predictors:
//   Lorenzo: from the seven lower neighbours of the unit cube (missing = 0); suits the small,
//            smooth lattices of control points.
//   Interpolation: multi-resolution. The points whose coordinates are all multiples of S (the
//            largest power of two below the longest axis) are Lorenzo-predicted on their own
//            lattice; then for s = S/2, ..., 1 the points at odd multiples of s are predicted along
//            x, then y, then z from the known points at +-s (cubic (-a + 9b + 9c - d) / 16 where
//            +-3s exist, linear (b + c) / 2 where +-s exist, else the one neighbour; the integer
//            forms round both down). Suits samples.
// Codes are zigzag varints (1 byte when |code| < 64), then an entropy stage: a zstd frame, or a
// lanes frame (entropy/lanes_coder.hpp: interleaved rANS, decoded by a GPU warp as by a CPU core);
// by default the lanes frame unless zstd's is more than 2% smaller (EntropyCoding). zstd wins on
// small and smooth payloads (its matches code runs of zeros); lanes on noisy ones (about 1%
// smaller on a scan's splines, and the GPU decodes them).
//
// Coded payload bytes: [0, 8) f64 step; [8] u8 predictor; integer forms: [9, 17) i64 base; then
// one frame (zstd, or lanes: it starts with "AFL1") holding the varints, one per value, in the
// predictor's visiting order (raster order for Lorenzo).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "afam/base/huge_pages.hpp"
#include "afam/entropy/entropy_stage.hpp"
#include "afam/entropy/lanes_coder.hpp"
#include "afam/format/compact_form.hpp"
#include "afam/format/partition.hpp"

namespace afam {

/// Payload byte 8: the predictor and its form (see above).
enum class Predictor : uint8_t {
  Lorenzo = 0,
  Interpolation = 1,
  IntegerLorenzo = 2,
  IntegerInterpolation = 3
};

/// True for the integer forms (index flag bit 9 in a file: readers before them refuse the file).
inline bool isIntegerForm(Predictor p) { return uint8_t(p) >= uint8_t(Predictor::IntegerLorenzo); }

/// Bytes before the zstd frame in a coded payload: double forms (step, predictor), integer forms
/// (step, predictor, base). The smallest coded payload is longer than kCodedHeaderBytes.
constexpr size_t kCodedHeaderBytes = 9;
constexpr size_t kIntegerCodedHeaderBytes = 17;

/// Whether a stored coded payload names an integer form (what index flag bit 9 says of it).
inline bool payloadIsIntegerCoded(const uint8_t* stored, size_t bytes) {
  return bytes > kCodedHeaderBytes && isIntegerForm(Predictor(stored[8]));
}

/// Bytes of a stored coded payload's header (before its frame): 9, or 17 for the integer forms.
inline size_t codedHeaderBytes(const uint8_t* stored, size_t bytes) {
  return payloadIsIntegerCoded(stored, bytes) ? kIntegerCodedHeaderBytes : kCodedHeaderBytes;
}

/// Whether a stored coded payload's frame is a lanes frame (what index flag bit 13 says of it).
inline bool payloadIsLanesCoded(const uint8_t* stored, size_t bytes) {
  const size_t head = codedHeaderBytes(stored, bytes);
  return bytes > head && lanes::isLanesFrame(stored + head, bytes - head);
}

/// The form to code `values` (count of them) with at `step`: the integer form of `family`
/// (Lorenzo or Interpolation) when every value lies within 2^26 steps of the values' middle, else
/// `family` itself.
Predictor choosePredictorForm(const float* values, size_t count, double step, Predictor family);

/// Values a block does not need (its missing samples, whose given values are the encoder's
/// filling of the holes): those whose bit is clear in `valid` (block_mask.hpp's words; nullptr:
/// every value counts) are free. A free value is coded as its own prediction (code 0, which costs
/// next to nothing; readers need no mask for it) when that prediction lies within `slack` steps of
/// the given value, and as given otherwise: slack 0 codes the filling as it is, kAnySlack frees
/// every hole (their predictions may then wander far from the valid values near them, which costs
/// the valid values' residuals; a slack of a few steps keeps them near the filling).
struct FreeValues {
  static constexpr int64_t kAnySlack = int64_t(1) << 62;
  const uint32_t* valid = nullptr;
  int64_t slack = kAnySlack;
  /// Whether value i is free: its bit in `valid` is clear.
  bool isFree(int64_t i) const { return valid && ((valid[i >> 5] >> (i & 31)) & 1u) == 0; }
};

/// Predicts, quantizes with `step` and codes `values` (n[0] * n[1] * n[2], x fastest) with the
/// predictor as given. Returns false (and leaves `out` empty) when a residual code would exceed
/// 2^50 (step far too small), or, for an integer form, when the values do not fit it.
/// `reconstructed` receives the decoded values (float), as decodeValues would produce them.
/// `free`: the values that need not be kept (FreeValues); the interpolation predictors only.
bool encodeValues(const float* values, Int3 n, double step, Predictor predictor,
                  EntropyCoding coding, std::vector<uint8_t>& out,
                  std::vector<float>& reconstructed, FreeValues free = {});

/// The sizes of the entropy frames formed for a payload's codes, 0 where not formed: the zstd
/// frame at the coding's level and the lanes frame (Auto forms both and keeps one: keepsLanes).
struct FrameSizes {
  size_t zstd = 0, lanes = 0;
};

/// Whether a payload's lanes frame (of `frameBytes`, coding `values` values; `trial` its first
/// coding's frames) is kept without trying zstd at the slow level, for a noisy block's codes (a
/// caller's judgement: white noise of half the bound or more): at most kLanesSure of the trial's
/// zstd frame at a fast level, with kLanesSureValues values or more. Measured on 1,704 payloads
/// (the corpus at RMSE 1e-2, 1e-3 and max error 1e-3, whole and in 4^3 blocks of 2 levels, the head
/// MRI made large with noise 2.5 and 6 and with --detail 18): zstd at level 15 was never more than
/// kLanesMargin smaller there. It was on smaller payloads (up to 10% on 2,500 values of the head
/// MRI in blocks of about 14^3), and it can be on smooth periodic values at a coarse step, whose
/// codes repeat (test_block_codec.cpp); those cost little to code again, or are not noise.
constexpr double kLanesSure = 0.9;
constexpr size_t kLanesSureValues = 16384;
bool lanesFrameSure(FrameSizes trial, size_t frameBytes, size_t values);

/// Codes the entropy frame of a coded payload of `values` values again with `coding` (the header's
/// `head` bytes and the last `tail` bytes kept as they are): an encoder compares its candidates
/// coded at a fast zstd level and gives only the one it keeps the slow level's frame. The payload
/// decodes to the same values. `trial`: the frames formed when it was first coded (encodeQuantized
/// with the same stage), where known: a lanes frame is then not formed again to be compared (the
/// same bytes). Throws FormatError when the frame does not decode, or the new frame does not
/// decode to the same symbols (checked).
void recodeFrame(std::vector<uint8_t>& payload, size_t head, size_t tail, size_t values,
                 EntropyCoding coding, FrameSizes trial = {});

/// The values as encodeValues would reconstruct them, without the entropy coding (to choose a
/// step).
bool quantizeValues(const float* values, Int3 n, double step, Predictor predictor,
                    std::vector<float>& reconstructed, FreeValues free = {});

/// Order-0 entropy, in bytes, of the codes encodeValues would produce (a cheap estimate of its
/// coded size, to skip coding a candidate that cannot win); infinity when the step does not fit.
double estimateCodedBytes(const float* values, Int3 n, double step, Predictor predictor,
                          FreeValues free = {});

/// One quantization of values (quantizeValues below), kept so that an encoder estimates and codes
/// the step its ladder chose without quantizing the values again. Its buffers keep their capacity
/// from one use to the next.
struct QuantizedValues {
  Int3 n{};
  double step = 0;
  Predictor predictor = Predictor::Lorenzo;
  int64_t base = 0;               ///< the integer forms' base
  HugePageVector<int32_t> k;      ///< the integer forms' values in steps (less base)
  HugePageVector<int64_t> codes;  ///< the residual codes encodeValues stores, once hasCodes
  bool hasCodes = false;          ///< the integer forms' residuals are formed when first asked
  HugePageVector<float> reconstructed;  ///< the values as decoded
};

/// quantizeValues, keeping the quantization in q (q.reconstructed the values as decoded).
bool quantizeValues(const float* values, Int3 n, double step, Predictor predictor,
                    QuantizedValues& q, FreeValues free = {});

/// encodeValues of the values q holds quantized: the same bytes, without quantizing again.
/// Returns the sizes of the frames formed.
FrameSizes encodeQuantized(QuantizedValues& q, EntropyCoding coding, std::vector<uint8_t>& out);

/// estimateCodedBytes of the values q holds quantized.
double estimateQuantizedBytes(QuantizedValues& q);

/// The share of an integer form's coded bytes that a value set's double form (Lorenzo or
/// Interpolation) must code under to be kept instead: the integer form decodes about 2.7x faster.
constexpr double kDoubleFormShare = 0.98;

/// lorenzoFormCannotWin's share of the order-0 estimates.
constexpr double kLorenzoFormsAlike = 0.99;

/// Whether the Lorenzo form of `integerForm`'s values (their IntegerLorenzo quantization, coded
/// into `payload` at an Auto coding's trial, its frames `trial`), quantized at the same step,
/// codes to at least kDoubleFormShare of `payload`, judged without coding it: the payload kept its
/// lanes frame and zstd's trial frame was no smaller (an order-0 coder coded the codes best, and
/// its bytes stand to the order-0 estimate alike for both forms' codes), and the Lorenzo form's
/// estimate is at least kLorenzoFormsAlike of the integer form's. `values`: the values
/// integerForm quantized; `lorenzoForm`: a buffer for their Lorenzo form. Measured with both forms
/// coded over the 8,173 splines' control points of the head made 1204x1480x1264 (noise 2.5, RMSE
/// 1e-2): the 6,341 it judges coded at least 0.9915 of the integer form's bytes; where zstd's frame
/// was the smaller, 22 blocks of a slab of it whose estimates were as alike coded under 0.98.
bool lorenzoFormCannotWin(QuantizedValues& integerForm, const std::vector<uint8_t>& payload,
                          FrameSizes trial, const float* values, QuantizedValues& lorenzoForm);

/// Decodes a coded payload of n[0] * n[1] * n[2] values into out. Throws FormatError (with
/// `where` in the message) when the bytes are not a valid coded payload of that size.
void decodeValues(const uint8_t* data, size_t bytes, Int3 n, float* out, const char* where);

/// Decodes a coded payload as decodeValues does, into its compact form when it is integer-coded
/// and that form takes at most maxShare of the floats' bytes; otherwise out holds the floats
/// (width 0). out is resized to what it holds.
CompactForm decodeValuesCompact(const uint8_t* data, size_t bytes, Int3 n, double maxShare,
                                std::vector<float>& out, const char* where);

}  // namespace afam
