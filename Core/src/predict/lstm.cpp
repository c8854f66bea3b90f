// SPDX-License-Identifier: BSD-3-Clause
#include "afam/predict/lstm.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>

#include "afam/base/errors.hpp"
#include "afam/base/hash.hpp"

#ifndef AFAM_DEFAULT_LSTM_WEIGHTS
#define AFAM_DEFAULT_LSTM_WEIGHTS "data/lstm_pose_v1.bin"
#endif

namespace afam {

namespace {

struct Reader {
  const std::vector<unsigned char>& buf;
  std::size_t pos;
  const std::string& path;
  void need(std::size_t n, const char* what) {
    if (pos + n > buf.size())
      throw FormatError("LSTM weights '" + path + "': truncated while reading " + what);
  }
  uint32_t u32(const char* what) {
    need(4, what);
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= uint32_t(buf[pos + i]) << (8 * i);
    pos += 4;
    return v;
  }
  float f32(const char* what) {
    const uint32_t u = u32(what);
    float f;
    std::memcpy(&f, &u, 4);
    return f;
  }
  std::vector<float> floats(std::size_t n, const char* what) {
    need(n * 4, what);
    std::vector<float> v(n);
    for (std::size_t i = 0; i < n; ++i) v[i] = f32(what);
    for (float x : v)
      if (!std::isfinite(x))
        throw FormatError("LSTM weights '" + path + "': non-finite value in " + what);
    return v;
  }
};

inline float sigmoid(float x) { return 1.0f / (1.0f + std::exp(-x)); }

}  // namespace

LstmWeights loadLstmWeights(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot open LSTM weights '" + path + "'");
  std::vector<unsigned char> buf((std::istreambuf_iterator<char>(in)),
                                 std::istreambuf_iterator<char>());
  if (in.bad()) throw IoError("reading LSTM weights '" + path + "' failed");
  if (buf.size() < 8 + 4 || std::memcmp(buf.data(), "AFLSTM\0\0", 8) != 0)
    throw FormatError("LSTM weights '" + path + "': bad magic (not an AFLSTM file)");
  const std::size_t body = buf.size() - 4;
  uint32_t stored = 0;
  for (int i = 0; i < 4; ++i) stored |= uint32_t(buf[body + i]) << (8 * i);
  if (fnv1a32(buf.data(), body) != stored)
    throw FormatError("LSTM weights '" + path + "': checksum mismatch (corrupt file)");
  Reader r{buf, 8, path};
  LstmWeights w;
  const uint32_t version = r.u32("version");
  if (version != LstmWeights::kVersion)
    throw FormatError("LSTM weights '" + path + "': version " + std::to_string(version) +
                      ", this build reads version " + std::to_string(LstmWeights::kVersion));
  w.input = r.u32("input size");
  w.hidden = r.u32("hidden size");
  w.output = r.u32("output size");
  w.window = r.u32("window");
  w.deltaScale = r.f32("delta scale");
  w.flags = r.u32("flags");
  if (w.input != 6 || w.output != 3 || w.hidden < 1 || w.hidden > 1024 || w.window < 1 ||
      w.window > 1024 || !(w.deltaScale > 0))
    throw FormatError("LSTM weights '" + path + "': unsupported shape (input " +
                      std::to_string(w.input) + ", hidden " + std::to_string(w.hidden) +
                      ", output " + std::to_string(w.output) + "); expected 6 inputs, 3 outputs");
  const std::size_t I = w.input, H = w.hidden, O = w.output;
  w.wIh = r.floats(4 * H * I, "W_ih");
  w.wHh = r.floats(4 * H * H, "W_hh");
  w.bias = r.floats(4 * H, "bias");
  w.wOut = r.floats(O * H, "W_out");
  w.bOut = r.floats(O, "b_out");
  w.testSteps = r.u32("test steps");
  if (w.testSteps > 4096) throw FormatError("LSTM weights '" + path + "': bad test vector length");
  w.testInput = r.floats(std::size_t(w.testSteps) * I, "test input");
  w.testOutput = r.floats(O, "test output");
  if (r.pos != body) throw FormatError("LSTM weights '" + path + "': trailing bytes");
  return w;
}

std::vector<float> lstmForward(const LstmWeights& w, const float* seq, int steps) {
  const int I = int(w.input), H = int(w.hidden), O = int(w.output);
  std::vector<float> h(H, 0.f), c(H, 0.f), gates(4 * H);
  for (int t = 0; t < steps; ++t) {
    const float* x = seq + std::size_t(t) * I;
    for (int g = 0; g < 4 * H; ++g) {
      float s = w.bias[g];
      const float* wi = &w.wIh[std::size_t(g) * I];
      for (int k = 0; k < I; ++k) s += wi[k] * x[k];
      const float* wh = &w.wHh[std::size_t(g) * H];
      for (int k = 0; k < H; ++k) s += wh[k] * h[k];
      gates[g] = s;
    }
    for (int k = 0; k < H; ++k) {
      const float ig = sigmoid(gates[k]), fg = sigmoid(gates[H + k]);
      const float gg = std::tanh(gates[2 * H + k]), og = sigmoid(gates[3 * H + k]);
      c[k] = fg * c[k] + ig * gg;
      h[k] = og * std::tanh(c[k]);
    }
  }
  std::vector<float> out(O);
  for (int o = 0; o < O; ++o) {
    float s = w.bOut[o];
    for (int k = 0; k < H; ++k) s += w.wOut[std::size_t(o) * H + k] * h[k];
    out[o] = s;
  }
  return out;
}

std::string defaultLstmWeightsPath() {
  if (const char* env = std::getenv("AFAM_LSTM_WEIGHTS"); env && *env) return env;
  return AFAM_DEFAULT_LSTM_WEIGHTS;
}

Vec3 lstmNextPosition(const LstmWeights& w, const std::vector<Vec3>& P) {
  const std::size_t n = P.size();
  if (n < 2)
    throw InvalidArgument("lstm: a prediction needs at least two positions, got " +
                          std::to_string(n));
  const std::size_t steps = std::min<std::size_t>(w.window, n - 1);
  std::vector<float> feat(steps * 6);
  const double inv = 1.0 / w.deltaScale;
  for (std::size_t s = 0; s < steps; ++s) {
    const std::size_t t = n - steps + s;  // step t uses P[t] - P[t-1]
    for (int k = 0; k < 3; ++k) {
      feat[s * 6 + k] = static_cast<float>((P[t][k] - P[t - 1][k]) * inv);
      feat[s * 6 + 3 + k] = static_cast<float>(P[t][k]);
    }
  }
  const std::vector<float> r = lstmForward(w, feat.data(), int(steps));
  Vec3 next;
  const bool residual = (w.flags & LstmWeights::kFlagResidual) != 0;
  for (int k = 0; k < 3; ++k) {
    const double lin = residual ? P[n - 1][k] + (P[n - 1][k] - P[n - 2][k]) : P[n - 1][k];
    next[k] = lin + w.deltaScale * r[k];
  }
  return next;
}

bool LstmPredictor::predict(const std::vector<Camera>& history, Camera& next) const {
  if (history.size() < 2) return false;
  const std::size_t used = std::min<std::size_t>(history.size(), std::size_t(w_.window) + 1);
  std::vector<Vec3> eyes;
  eyes.reserve(used);
  for (std::size_t i = history.size() - used; i < history.size(); ++i)
    eyes.push_back(history[i].eye);
  const Camera& last = history.back();
  next = Camera::fromPose(poseFromPosition(lstmNextPosition(w_, eyes)), last.width, last.height);
  return true;
}

}  // namespace afam
