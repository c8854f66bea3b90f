// SPDX-License-Identifier: BSD-3-Clause
#include "afam/format/block_codec.hpp"

#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>

#include "afam/base/errors.hpp"
#include "afam/format/rounded_points.hpp"
#include "codec_common.hpp"
#include "integer_codec.hpp"

namespace afam {

namespace {

using codec::coarsestSpacing;
using codec::interpolate;
using codec::Lattice;
using codec::lorenzo;
using codec::roundHalfEven;

constexpr double kMaxCode = 1125899906842624.0;  // 2^50: residual codes beyond are refused

template <typename Fn>
void interpolation(const Lattice& L, const double* q, Fn&& fn) {
  const int S = coarsestSpacing(L.n);
  lorenzo(L, q, S, fn);
  const int64_t strideY = L.n[0], strideZ = int64_t(L.n[0]) * L.n[1];
  for (int s = S / 2; s >= 1; s /= 2) {
    const int s2 = 2 * s;
    for (int z = 0; z < L.n[2]; z += s2)
      for (int y = 0; y < L.n[1]; y += s2) {
        const int64_t row = L.index(0, y, z);
        for (int x = s; x < L.n[0]; x += s2) fn(row + x, interpolate(x, s, L.n[0], q + row, 1));
      }
    for (int z = 0; z < L.n[2]; z += s2)
      for (int y = s; y < L.n[1]; y += s2) {
        const int64_t row = L.index(0, y, z), column = L.index(0, 0, z);
        for (int x = 0; x < L.n[0]; x += s)
          fn(row + x, interpolate(y, s, L.n[1], q + column + x, strideY));
      }
    for (int z = s; z < L.n[2]; z += s2)
      for (int y = 0; y < L.n[1]; y += s) {
        const int64_t row = L.index(0, y, z), pillar = L.index(0, y, 0);
        for (int x = 0; x < L.n[0]; x += s)
          fn(row + x, interpolate(z, s, L.n[2], q + pillar + x, strideZ));
      }
  }
}

template <typename Fn>
void visit(Predictor p, const Lattice& L, const double* q, Fn&& fn) {
  if (p == Predictor::Lorenzo)
    lorenzo(L, q, 1, fn);
  else
    interpolation(L, q, fn);
}

/// One value's code: round((value - pred) / step) (nearbyint's result; beyond kRoundExact, > 2^50
/// and refused, x itself); 0 for a free value whose code lies within its slack.
inline double codeOf(double value, double pred, double step, bool isFree, int64_t slack) {
  const double x = (value - pred) / step;
  const double q = std::fabs(x) < codec::kRoundExact ? roundHalfEven(x) : x;
  return isFree && std::fabs(q) <= double(slack) ? 0.0 : q;
}

/// Predicts every value from the values already reconstructed (in the predictor's order) and
/// quantizes the prediction residual: code = round((v - prediction) / step), reconstruction =
/// prediction + code * step, so each reconstructed value lies within step / 2 of its value.
/// false when a code exceeds 2^50. Lorenzo without free values walks four rows at once
/// (lorenzoFourRows: each value waits for its prediction, a chain of dependent divisions), its
/// codes stored at their values' places, which is its visiting order.
bool predictQuantize(const float* values, Int3 n, double step, Predictor predictor,
                     HugePageVector<int64_t>& codes, HugePageVector<float>& reconstructed,
                     FreeValues free) {
  const size_t count = size_t(n[0]) * size_t(n[1]) * size_t(n[2]);
  // The thread's buffer, not cleared: every value a prediction reads is written first (as in
  // decodeValues).
  double* r = threadScratch<double>(ScratchSlot::Doubles, count);
  bool ok = true;
  // Value i's code (r[i] its reconstruction); false (and ok false) past 2^50.
  auto quantize = [&](int64_t i, double pred, int64_t& code) {
    const double q = codeOf(double(values[i]), pred, step, free.isFree(i), free.slack);
    if (!(std::fabs(q) <= kMaxCode)) {
      ok = false;
      r[size_t(i)] = double(values[i]);
      return false;
    }
    code = int64_t(q);
    r[size_t(i)] = pred + q * step;
    return true;
  };
  if (predictor == Predictor::Lorenzo && !free.valid) {
    codes.resize(count);
    codec::lorenzoFourRows(Lattice{n}, r,
                           [&](int64_t i, double pred) { quantize(i, pred, codes[size_t(i)]); });
  } else {
    codes.clear();
    codes.reserve(count);
    visit(predictor, Lattice{n}, r, [&](int64_t i, double pred) {
      int64_t code;
      if (quantize(i, pred, code)) codes.push_back(code);
    });
  }
  reconstructed.resize(count);
  for (size_t i = 0; i < count; ++i) reconstructed[i] = static_cast<float>(r[i]);
  return ok;
}

}  // namespace

Predictor choosePredictorForm(const float* values, size_t count, double step, Predictor family) {
  int64_t base;
  thread_local HugePageVector<int32_t> k;
  if (!(step > 0) || !std::isfinite(step) || !codec::integerQuantize(values, count, step, base, k))
    return family;
  return family == Predictor::Lorenzo ? Predictor::IntegerLorenzo : Predictor::IntegerInterpolation;
}

namespace {
/// The residual codes of q: an integer form's are formed from its k when first asked.
const HugePageVector<int64_t>& codesOf(QuantizedValues& q) {
  if (!q.hasCodes) {
    int32_t* r = threadScratch<int32_t>(ScratchSlot::Words, q.k.size());  // the decoder's slot
    codec::integerResiduals(q.predictor, q.n, q.k, r);
    q.codes.assign(r, r + q.k.size());
    q.hasCodes = true;
  }
  return q.codes;
}
}  // namespace

bool quantizeValues(const float* values, Int3 n, double step, Predictor predictor,
                    QuantizedValues& q, FreeValues free) {
  q.hasCodes = false;
  if (!(step > 0) || !std::isfinite(step) || uint8_t(predictor) > 3) return false;
  q.n = n;
  q.step = step;
  q.predictor = predictor;
  q.base = 0;
  if (!isIntegerForm(predictor))
    return q.hasCodes = predictQuantize(values, n, step, predictor, q.codes, q.reconstructed, free);
  const size_t count = size_t(n[0]) * size_t(n[1]) * size_t(n[2]);
  if (!codec::integerQuantize(values, count, step, q.base, q.k)) return false;
  if (free.valid && predictor == Predictor::IntegerInterpolation) {
    // A free value may take its prediction, which changes its k: the predictor's order decides.
    int32_t* r = threadScratch<int32_t>(ScratchSlot::Words, count);
    codec::integerResiduals(predictor, n, q.k, r, free);
    q.codes.assign(r, r + count);
    q.hasCodes = true;
  }
  q.reconstructed.resize(count);
  codec::integerValues(q.base, q.k.data(), count, step, q.reconstructed.data());
  return true;
}

bool quantizeValues(const float* values, Int3 n, double step, Predictor predictor,
                    std::vector<float>& reconstructed, FreeValues free) {
  thread_local QuantizedValues q;
  if (!quantizeValues(values, n, step, predictor, q, free)) return false;
  reconstructed.assign(q.reconstructed.begin(), q.reconstructed.end());
  return true;
}

namespace {
/// Order-0 entropy of the codes, in bits: a histogram where they span few values, else sorted.
double orderZeroBits(const HugePageVector<int64_t>& codes) {
  if (codes.empty()) return 0;
  int64_t lo = codes[0], hi = codes[0];  // one pass, no iterators kept: it vectorizes
  for (const int64_t c : codes) {
    lo = std::min(lo, c);
    hi = std::max(hi, c);
  }
  const double total = double(codes.size());
  double bits = 0;
  auto add = [&](double count) {
    if (count > 0) bits -= count * std::log2(count / total);
  };
  if (uint64_t(hi - lo) < (uint64_t(1) << 16)) {
    thread_local std::vector<uint32_t> histogram;
    histogram.assign(size_t(hi - lo) + 1, 0);
    for (const int64_t c : codes) ++histogram[size_t(c - lo)];
    for (const uint32_t h : histogram) add(double(h));
    return bits;
  }
  thread_local std::vector<int64_t> sorted;
  sorted.assign(codes.begin(), codes.end());
  std::sort(sorted.begin(), sorted.end());
  for (size_t i = 0; i < sorted.size();) {
    size_t j = i;
    while (j < sorted.size() && sorted[j] == sorted[i]) ++j;
    add(double(j - i));
    i = j;
  }
  return bits;
}
}  // namespace

double estimateQuantizedBytes(QuantizedValues& q) {
  const double bits = orderZeroBits(codesOf(q));
  return double(isIntegerForm(q.predictor) ? kIntegerCodedHeaderBytes : kCodedHeaderBytes) +
         bits / 8;
}

double estimateCodedBytes(const float* values, Int3 n, double step, Predictor predictor,
                          FreeValues free) {
  thread_local QuantizedValues q;
  if (!quantizeValues(values, n, step, predictor, q, free))
    return std::numeric_limits<double>::infinity();
  return estimateQuantizedBytes(q);
}

bool lorenzoFormCannotWin(QuantizedValues& integerForm, const std::vector<uint8_t>& payload,
                          FrameSizes trial, const float* values, QuantizedValues& lorenzoForm) {
  if (integerForm.predictor != Predictor::IntegerLorenzo ||
      !payloadIsLanesCoded(payload.data(), payload.size()) ||
      (trial.zstd > 0 && trial.lanes > trial.zstd))
    return false;
  return quantizeValues(values, integerForm.n, integerForm.step, Predictor::Lorenzo, lorenzoForm) &&
         estimateQuantizedBytes(lorenzoForm) >=
             kLorenzoFormsAlike * estimateQuantizedBytes(integerForm);
}

FrameSizes encodeQuantized(QuantizedValues& q, EntropyCoding coding, std::vector<uint8_t>& out) {
  const HugePageVector<int64_t>& codes = codesOf(q);
  thread_local std::vector<uint8_t> varints;
  varints.clear();
  varints.reserve(codes.size() + codes.size() / 4);
  for (const int64_t c : codes) codec::putVarint(codec::zigzag(c), varints);
  out.resize(kCodedHeaderBytes);
  std::memcpy(out.data(), &q.step, 8);
  out[8] = uint8_t(q.predictor);
  if (isIntegerForm(q.predictor)) {
    out.resize(kIntegerCodedHeaderBytes);
    std::memcpy(out.data() + kCodedHeaderBytes, &q.base, 8);
  }
  return codec::appendEntropyFrame(varints, coding, out);
}

bool encodeValues(const float* values, Int3 n, double step, Predictor predictor,
                  EntropyCoding coding, std::vector<uint8_t>& out,
                  std::vector<float>& reconstructed, FreeValues free) {
  out.clear();
  thread_local QuantizedValues q;
  if (!quantizeValues(values, n, step, predictor, q, free)) return false;
  encodeQuantized(q, coding, out);
  reconstructed.assign(q.reconstructed.begin(), q.reconstructed.end());
  return true;
}

bool lanesFrameSure(FrameSizes trial, size_t frameBytes, size_t values) {
  return trial.zstd > 0 && trial.lanes == frameBytes && values >= kLanesSureValues &&
         double(frameBytes) <= kLanesSure * double(trial.zstd);
}

void recodeFrame(std::vector<uint8_t>& payload, size_t head, size_t tail, size_t values,
                 EntropyCoding coding, FrameSizes trial) {
  if (payload.size() <= head + tail) throw codec::badPayload("recode", "has no frame");
  size_t got = 0;
  const size_t frameBytes = payload.size() - head - tail;
  const bool holdsLanes = lanes::isLanesFrame(payload.data() + head, frameBytes);
  const uint8_t* symbols =
      codec::unpackFrame(payload.data() + head, frameBytes, values * 10, 0, "recode", got);
  thread_local std::vector<uint8_t> varints;
  varints.assign(symbols, symbols + got);
  // The lanes frame's size where known (the payload's own frame, or the trial's): Auto then forms
  // only the zstd frame, and the lanes frame again only where it is kept in place of a zstd one.
  const size_t lanesBytes = holdsLanes ? frameBytes : trial.lanes;
  std::vector<uint8_t> out(payload.begin(), payload.begin() + std::ptrdiff_t(head));
  if (coding.stage == EntropyStage::Auto && lanesBytes > 0) {
    codec::appendZstdFrame(varints, coding.zstdLevel, out);
    if (keepsLanes(double(lanesBytes), double(out.size() - head))) {
      if (holdsLanes) return;  // the payload keeps its frame
      out.resize(head);
      lanes::appendFrame(varints, out);
    }
  } else {
    codec::appendEntropyFrame(varints, coding, out);
  }
  out.insert(out.end(), payload.end() - std::ptrdiff_t(tail), payload.end());
  // The new frame holds the very symbols (lossless coders; checked, for the encoder measures a
  // kept interpolant on its trial frame's decoding and does not decode the payload again).
  size_t again = 0;
  const uint8_t* back = codec::unpackFrame(out.data() + head, out.size() - head - tail, values * 10,
                                           0, "recode", again);
  if (again != got || std::memcmp(back, varints.data(), got) != 0)
    throw codec::badPayload("recode", "does not decode to the frame it was coded from");
  payload = std::move(out);
}

namespace {
/// A coded payload's quantization step, after checking its header.
double checkedStep(const uint8_t* data, size_t bytes, const char* where) {
  if (bytes < kCodedHeaderBytes + 1) throw codec::badPayload(where, "shorter than its header");
  double step;
  std::memcpy(&step, data, 8);
  if (!(step > 0) || !std::isfinite(step))
    throw codec::badPayload(where, "has an invalid quantization step");
  if (data[8] > uint8_t(Predictor::IntegerInterpolation))
    throw codec::badPayload(where, "names unknown predictor " + std::to_string(data[8]));
  return step;
}
}  // namespace

CompactForm decodeValuesCompact(const uint8_t* data, size_t bytes, Int3 n, double maxShare,
                                std::vector<float>& out, const char* where) {
  checkedStep(data, bytes, where);
  if (isIntegerForm(Predictor(data[8])))
    return codec::decodeIntegerCompact(data, bytes, n, maxShare, out, where);
  out.resize(size_t(n[0]) * size_t(n[1]) * size_t(n[2]));
  decodeValues(data, bytes, n, out.data(), where);
  return CompactForm{};
}

void decodeValues(const uint8_t* data, size_t bytes, Int3 n, float* out, const char* where) {
  const double step = checkedStep(data, bytes, where);
  if (isIntegerForm(Predictor(data[8]))) return codec::decodeInteger(data, bytes, n, out, where);
  const size_t count = size_t(n[0]) * size_t(n[1]) * size_t(n[2]);
  // The varints (at most 10 a value) in the thread's buffer; the doubles likewise, reused
  // without being cleared: every value the predictors read is written first.
  size_t got = 0;
  const uint8_t* varints = codec::unpackFrame(data + kCodedHeaderBytes, bytes - kCodedHeaderBytes,
                                              count * 10, 0, where, got);
  double* r = threadScratch<double>(ScratchSlot::Doubles, count);
  size_t pos = 0;
  visit(Predictor(data[8]), Lattice{n}, r, [&](int64_t i, double pred) {
    uint64_t u;
    if (pos < got && varints[pos] < 0x80) {
      u = varints[pos++];  // |code| < 64: one byte, the common case
    } else {
      u = 0;
      for (int shift = 0;; shift += 7) {
        if (pos >= got || shift > 63) throw codec::badPayload(where, "ends inside a residual");
        const uint8_t b = varints[pos++];
        u |= uint64_t(b & 0x7f) << shift;
        if (!(b & 0x80)) break;
      }
    }
    const int64_t code = int64_t(u >> 1) ^ -int64_t(u & 1);
    if (!(std::fabs(double(code)) <= kMaxCode))
      throw codec::badPayload(where, "holds an absurd residual");
    r[size_t(i)] = pred + double(code) * step;
  });
  if (pos != got)
    throw codec::badPayload(where,
                            "has " + std::to_string(got - pos) + " bytes after its last residual");
  for (size_t i = 0; i < count; ++i) {
    const float v = static_cast<float>(r[i]);
    if (!std::isfinite(v)) throw codec::badPayload(where, "decodes to a value beyond float32");
    out[i] = v;
  }
}

// ------------------------------------------------------------------------------------------------
// Rounded interpolant points (rounded_points.hpp). This file is compiled with -ffp-contract=off:
// the sum below must round the product first.

namespace {
/// roundPoints without a branch a point (so that the loop vectorizes): a point out of range is
/// coded as 0 and reported by the result.
template <bool KeepCodes>
bool roundEvery(float* points, size_t count, double q, int64_t* k) {
  const double inverse = 1.0 / q;
  bool ok = true;
  for (size_t i = 0; i < count; ++i) {
    double code;
    ok &= roundedPoint(points[i], q, inverse, &points[i], &code);
    if (KeepCodes) k[i] = int64_t(code);
  }
  return ok;
}
}  // namespace

bool roundPoints(float* points, size_t count, double q, int64_t* k) {
  return k ? roundEvery<true>(points, count, q, k) : roundEvery<false>(points, count, q, nullptr);
}

bool roundPointsSpan(float* points, size_t count, double q, uint64_t& span) {
  const double inverse = 1.0 / q;
  bool ok = true;
  // The codes' extremes as doubles (whole numbers below 2^53: exact), in a loop that vectorizes.
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (size_t i = 0; i < count; ++i) {
    double code;
    ok &= roundedPoint(points[i], q, inverse, &points[i], &code);
    lo = code < lo ? code : lo;
    hi = code > hi ? code : hi;
  }
  span = ok && count > 0 ? uint64_t(int64_t(hi) - int64_t(lo)) : 0;
  return ok;
}

int64_t pointCode(float c, double q) {
  int64_t k = 0;
  roundEvery<true>(&c, 1, q, &k);
  return k;
}

}  // namespace afam
