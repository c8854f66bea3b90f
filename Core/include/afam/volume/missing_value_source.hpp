// SPDX-License-Identifier: BSD-3-Clause
// A source whose fill value marks missing samples (a land mask's -999, a CT's padding value): the
// samples equal to it are read as NaN, which the encoder and `afam verify` take for missing.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>

#include "afam/volume/sample_type.hpp"
#include "afam/volume/volume_source.hpp"

namespace afam {

/// Why `value` cannot mark missing samples of `type` ("" when it can): NaN, infinite, or for
/// integer samples outside the type's range or not an integer; for float32, outside its range.
std::string missingValueProblem(double value, SampleType type);

class MissingValueSource : public WrappingSource {
 public:
  /// Throws InvalidArgument when `value` is NaN or infinite, or, for a source of integer samples
  /// (`type`), outside the type's range or not an integer (no sample could equal it).
  MissingValueSource(VolumeSource& inner, double value, SampleType type = SampleType::Float32);
  void readSlab(int64_t z0, int64_t zCount, float* out) override;
  void readRows(int64_t z0, int64_t zCount, int64_t y0, int64_t yCount, float* out) override;
  /// Samples read so far that equalled the value (a caller warns when none did).
  int64_t matches() const { return matches_.load(); }

 private:
  void mark(float* v, int64_t count);
  float value_;
  std::atomic<int64_t> matches_{0};
};

}  // namespace afam
