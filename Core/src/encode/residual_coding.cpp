// SPDX-License-Identifier: BSD-3-Clause
// A run's block coded in time as a residual (format version 3, in-time coding 2): the step
// before's model, as a reader decodes it, plus a coded difference of the same kind and NCP. For a
// spline the difference is between this step's least-squares fit at the model's NCP and the
// model's control points (by linearity, the fit of what the model misses); for samples and
// interpolants, whose NCP is the block's samples, between the samples and the model on them. The
// difference is quantized within the error budget, predicted in an integer form and coded as any
// coded payload (block_codec.hpp); the model it gives is measured on the block's samples.
#include <cmath>
#include <string>
#include <vector>

#include "afam/format/block_codec.hpp"
#include "block_encoding.hpp"

namespace afam {

namespace {

/// The model at this step: the one before plus the residual payload decoded as a reader decodes
/// it (decodeStoredPayload; for an interpolant, the interpolating spline of the residual), added
/// in the order the reader adds them.
FitResult applyResidual(const ModelEntry& before, const FitResult& model,
                        const std::vector<uint8_t>& bytes, const std::string& where) {
  ModelEntry probe = before;  // the kind and NCP; this payload's coding
  probe.coded = true;
  probe.integerCoded = payloadIsIntegerCoded(bytes.data(), bytes.size());
  probe.lanesCoded = payloadIsLanesCoded(bytes.data(), bytes.size());
  probe.roundedPoints = false;  // a residual's points are never rounded
  probe.storedSize = bytes.size();
  probe.size = payloadBytes(before.ncp);
  std::vector<float> residual(model.control.size());
  decodeStoredPayload(probe, bytes.data(), residual.data(), where);
  FitResult out = model;
  for (size_t i = 0; i < residual.size(); ++i) out.control[i] = out.control[i] + residual[i];
  return out;
}

/// RMSE and largest error of (base + q) against the samples.
ErrorStats errorOfSum(const std::vector<float>& base, const HugePageVector<float>& q,
                      const std::vector<float>& s) {
  ErrorStats es;
  double sum = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    const double d = double(base[i]) + double(q[i]) - double(s[i]);
    sum += d * d;
    es.maxError = std::max(es.maxError, std::fabs(d));
  }
  es.rmse = std::sqrt(sum / double(std::max<size_t>(s.size(), 1)));
  return es;
}

}  // namespace

bool codeResidualIfSmaller(const FitContext& c, const BlockExtent& e, BlockFitter& fitter,
                           const ModelEntry& before, const FitResult& model, BlockTask& t) {
  if (before.kind == BlockKind::Constant || !(c.bound > 0)) return false;
  const Int3 n = e.samples;
  const bool onSamples = before.kind != BlockKind::Spline;  // NCP = the block's samples
  const std::vector<float>& s = t.samples;
  std::vector<float> delta(model.control.size()), values;
  FitResult fitted;  // a spline's fit of this step at the model's NCP
  const BoundKind kind = c.opt.boundKind;
  double budget = c.bound;
  if (onSamples) {
    fitter.evaluateOnGrid(model, n, values);
    if (values.size() != s.size()) return false;
    for (size_t i = 0; i < s.size(); ++i) delta[i] = s[i] - values[i];
  } else {
    fitter.fitInto(s.data(), n, model.ncp, c.opt.degree, true, fitted);
    if (fitted.degree != model.degree) return false;
    if (kind == BoundKind::MaxError) {  // what the fit's worst sample leaves
      if (!(fitted.error.maxError < c.bound)) return false;
      budget = c.bound - fitted.error.maxError;
    } else {  // the rest of the RMSE, in quadrature
      if (!(fitted.error.rmse < c.bound)) return false;
      budget = std::sqrt(c.bound * c.bound - fitted.error.rmse * fitted.error.rmse);
    }
    for (size_t i = 0; i < delta.size(); ++i) delta[i] = fitted.control[i] - model.control[i];
  }
  const Predictor form = onSamples ? Predictor::IntegerInterpolation : Predictor::IntegerLorenzo;
  FitResult trial = model;
  auto keepsBound = [&](const HugePageVector<float>& q) {
    if (onSamples) return keeps(kind, errorOfSum(values, q, s), c.bound);
    for (size_t i = 0; i < q.size(); ++i) trial.control[i] = model.control[i] + q[i];
    trial.errorMeasured = false;
    if (kind == BoundKind::Rmse) return fitter.changeWithin(s.data(), n, fitted, trial, c.bound);
    fitter.measure(s.data(), n, trial);
    return keeps(kind, trial.error, c.bound);
  };
  // The trial step's quantization, and the last passing step's: the one coded (the thread's
  // buffers, kept between blocks).
  thread_local QuantizedValues quantized, kept;
  auto passes = [&](double k) {
    if (!quantizeValues(delta.data(), model.ncp, ladderStep(kind, budget, k), form, quantized) ||
        !keepsBound(quantized.reconstructed))
      return false;
    std::swap(quantized, kept);
    return true;
  };
  const int best = largestPassingStep(passes);
  if (best < 0 || kept.step != ladderStep(kind, budget, kStepFactors[best])) return false;
  std::vector<uint8_t> bytes;
  codeAtFileLevel(c.opt, bytes, 0, delta.size(), encodeQuantized(kept, trialCoding(c.opt), bytes));
  if (bytes.size() >= t.stored.size()) return false;
  const FitResult decoded = applyResidual(
      before, model, bytes, c.sourceName + " " + Partition::blockName(c.level, t.ijk));
  ModelEntry decodedEntry = before;
  decodedEntry.samples = n;
  const ErrorStats es = errorAsDecoded(decodedEntry, decoded.control.data(), t);
  if (!keeps(kind, es, c.bound)) return false;
  ModelEntry& m = t.entry;
  m.kind = before.kind;
  m.coded = true;
  m.integerCoded = payloadIsIntegerCoded(bytes.data(), bytes.size());
  m.lanesCoded = payloadIsLanesCoded(bytes.data(), bytes.size());
  m.ncp = before.ncp;
  m.degree = before.degree;
  m.roundedPoints = false;
  m.reference = false;
  m.residual = true;
  setError(t, es);
  t.stored = std::move(bytes);
  m.storedSize = t.stored.size();
  return true;
}

}  // namespace afam
