// SPDX-License-Identifier: BSD-3-Clause
#include "afam/volume/valid_mask_source.hpp"

#include <limits>

namespace afam {

void markInvalid(const uint8_t* valid, int64_t count, float* out) {
  const float missing = std::numeric_limits<float>::quiet_NaN();
  for (int64_t i = 0; i < count; ++i)
    if (valid[i] == 0) out[i] = missing;
}

ValidMaskSource::ValidMaskSource(VolumeSource& inner, const uint8_t* valid)
    : WrappingSource(inner), valid_(valid) {}

void ValidMaskSource::readSlab(int64_t z0, int64_t zCount, float* out) {
  inner_.readSlab(z0, zCount, out);
  const Index3 d = dims();
  markInvalid(valid_ + z0 * d[0] * d[1], d[0] * d[1] * zCount, out);
}

void ValidMaskSource::readRows(int64_t z0, int64_t zCount, int64_t y0, int64_t yCount, float* out) {
  inner_.readRows(z0, zCount, y0, yCount, out);
  const Index3 d = dims();
  for (int64_t z = 0; z < zCount; ++z)  // the rows asked for, plane by plane
    markInvalid(valid_ + ((z0 + z) * d[1] + y0) * d[0], d[0] * yCount, out + z * d[0] * yCount);
}

}  // namespace afam
