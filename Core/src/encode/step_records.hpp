// SPDX-License-Identifier: BSD-3-Clause
// One encoded step of a run as bytes (private to Core): what the first process of an EncodeTeam
// sends every other after it wrote the step, so that each codes its blocks of the next step
// against the same models (encode_run.cpp). The step's header (its partition and range) and every
// model as the file stores it, in the file's order. Processes of one team run the same build, so
// records are copied as they lie in memory (fitted_blocks.hpp).
#pragma once

#include <cstdint>
#include <vector>

#include "afam/encode/model_sink.hpp"

namespace afam {

/// Records the header and the models a sink receives, then hands them on to `next`.
class StepRecorder : public ModelSink {
 public:
  explicit StepRecorder(ModelSink& next) : next_(next) {}
  void begin(const VolumeHeader& h) override;
  void add(const ModelEntry& entry, const void* stored) override;
  /// Everything received so far, as bytes for replayStep.
  const std::vector<uint8_t>& bytes() const { return bytes_; }

 private:
  ModelSink& next_;
  std::vector<uint8_t> bytes_;
};

/// Hands the header and the models recorded by a StepRecorder to `sink`, in their order. Throws
/// FormatError when the bytes are cut short.
void replayStep(const std::vector<uint8_t>& bytes, ModelSink& sink);

}  // namespace afam
