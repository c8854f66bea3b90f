// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: the LSTM weights loader (loadLstmWeights), then a forward pass over the file's own
// test sequence and one prediction from three cameras. Input: one control byte (odd: recompute the
// trailing FNV-1a checksum after mutation, so mutations reach the parser behind it), then the
// file's bytes.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/base/hash.hpp"
#include "afam/predict/lstm.hpp"
#include "memory_file.hpp"

namespace {

// FNV-1a over the body, stored little-endian in the last four bytes (scripts/train_lstm.py).
void fixChecksum(std::vector<uint8_t>& b) {
  if (b.size() < 4) return;
  const uint32_t h = afam::fnv1a32(b.data(), b.size() - 4);
  for (int i = 0; i < 4; ++i)
    b[b.size() - 4 + static_cast<size_t>(i)] = static_cast<uint8_t>(h >> (8 * i));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static afam_fuzz::MemoryFile memory;
  std::vector<uint8_t> bytes(data + 1, data + size);
  if (data[0] & 1) fixChecksum(bytes);
  const std::string& path = memory.write(bytes.data(), bytes.size());
  try {
    afam::LstmWeights w = afam::loadLstmWeights(path);
    if (w.testSteps > 0)
      (void)afam::lstmForward(w, w.testInput.data(), static_cast<int>(w.testSteps));
    const afam::LstmPredictor predictor(std::move(w));
    std::vector<afam::Camera> history;
    for (int i = 0; i < 3; ++i)
      history.push_back(afam::Camera::fromPose(afam::Pose{1.2, 0.1 * i, 0.3}, 8, 8));
    afam::Camera next;
    (void)predictor.predict(history, next);
  } catch (const afam::Error&) {
  }
  return 0;
}
