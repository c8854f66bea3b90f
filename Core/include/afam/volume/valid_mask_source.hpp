// SPDX-License-Identifier: BSD-3-Clause
// A source whose samples are missing where a mask says so (VTK's vtkValidPointMask: one byte a
// sample, 0 = not valid, as a probe or a resampling leaves it): those samples are read as NaN,
// which the encoder takes for missing. The mask is read where the samples are, never copied.
#pragma once

#include <cstdint>
#include <string>

#include "afam/volume/volume_source.hpp"

namespace afam {

class ValidMaskSource : public WrappingSource {
 public:
  /// `valid`: dims[0] * dims[1] * dims[2] bytes of `inner`'s grid, x fastest; a 0 byte marks the
  /// sample missing. The mask must outlive the source.
  ValidMaskSource(VolumeSource& inner, const uint8_t* valid);
  void readSlab(int64_t z0, int64_t zCount, float* out) override;
  void readRows(int64_t z0, int64_t zCount, int64_t y0, int64_t yCount, float* out) override;

 private:
  const uint8_t* valid_;
};

/// Sets out[i] to NaN where valid[i] is 0, for `count` samples (what ValidMaskSource does to each
/// row it reads; also for a piece of an image masked before it is shared).
void markInvalid(const uint8_t* valid, int64_t count, float* out);

}  // namespace afam
