// SPDX-License-Identifier: BSD-3-Clause
// A small LSTM that predicts the next eye position from the last few, run live in plain C++.
// Trained offline by scripts/train_lstm.py (torch); the weights ship as data/lstm_pose_v1.bin.
// The file layout, the features and the gate order are documented in that script and must stay in
// step with it (the version field guards that; a test compares this forward pass with torch's).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "afam/predict/predictor.hpp"
#include "afam/scene/camera.hpp"

namespace afam {

struct LstmWeights {
  static constexpr uint32_t kVersion = 1;
  static constexpr uint32_t kFlagResidual = 1;  ///< output corrects linear extrapolation
  uint32_t input = 0, hidden = 0, output = 0, window = 0;
  float deltaScale = 0.05f;
  uint32_t flags = 0;
  std::vector<float> wIh;   ///< [4H][I], gates i, f, g, o (torch order)
  std::vector<float> wHh;   ///< [4H][H]
  std::vector<float> bias;  ///< [4H], b_ih + b_hh
  std::vector<float> wOut;  ///< [O][H]
  std::vector<float> bOut;  ///< [O]
  uint32_t testSteps = 0;
  std::vector<float> testInput;   ///< [testSteps][I]
  std::vector<float> testOutput;  ///< [O]: torch's head output for testInput
};

/// Reads and validates a weights file. Throws IoError (open/read) or FormatError (magic, version,
/// sizes, checksum, truncation), naming the file.
LstmWeights loadLstmWeights(const std::string& path);

/// The head output for a sequence of `steps` feature rows (steps x input floats), zero initial
/// state.
std::vector<float> lstmForward(const LstmWeights& w, const float* sequence, int steps);

/// The weights file shipped with the sources: $AFAM_LSTM_WEIGHTS if set, else the repository's
/// data/lstm_pose_v1.bin (path fixed at configure time).
std::string defaultLstmWeightsPath();

/// The LSTM's next eye position after `positions` (oldest first, at least two; the last window + 1
/// are used): features per step [ (P_t - P_{t-1}) / deltaScale, P_t ]; the prediction is
/// P_{t+1} = P_t + (P_t - P_{t-1}) + deltaScale * head with the residual flag, P_t + deltaScale *
/// head without it. Throws InvalidArgument for fewer than two positions.
Vec3 lstmNextPosition(const LstmWeights& w, const std::vector<Vec3>& positions);

/// "lstm": the trajectory camera (Camera::fromPose) at lstmNextPosition of the history's eyes.
class LstmPredictor : public Predictor {
 public:
  explicit LstmPredictor(LstmWeights weights) : w_(std::move(weights)) {}
  explicit LstmPredictor(const std::string& weightsPath)
      : LstmPredictor(loadLstmWeights(weightsPath)) {}
  const char* name() const override { return "lstm"; }
  /// False for fewer than two cameras.
  bool predict(const std::vector<Camera>& history, Camera& next) const override;
  const LstmWeights& weights() const { return w_; }

 private:
  LstmWeights w_;
};

}  // namespace afam
