// SPDX-License-Identifier: BSD-3-Clause
#include "afam/volume/missing_value_source.hpp"

#include <cfloat>
#include <cmath>
#include <limits>
#include <sstream>

#include "afam/base/errors.hpp"

namespace afam {

std::string missingValueProblem(double value, SampleType type) {
  std::ostringstream why;
  if (std::isnan(value)) {
    why << "is NaN (NaN samples are always missing; give the value that marks the others)";
  } else if (std::isinf(value)) {
    why << "is infinite";
  } else if (type != SampleType::Float32 && type != SampleType::Float64) {
    double lo = 0, hi = 0;
    sampleTypeRange(type, lo, hi);
    if (value < lo || value > hi)
      why << "lies outside the range [" << lo << ", " << hi << "] of " << sampleTypeName(type);
    else if (value != std::floor(value))
      why << "is not an integer, and the samples are " << sampleTypeName(type);
  } else if (type == SampleType::Float32 && std::fabs(value) > double(FLT_MAX)) {
    why << "lies outside float32's range";
  }
  return why.str();
}

MissingValueSource::MissingValueSource(VolumeSource& inner, double value, SampleType type)
    : WrappingSource(inner), value_(float(value)) {
  const std::string why = missingValueProblem(value, type);
  if (!why.empty()) {
    std::ostringstream msg;
    msg << "missing value " << value << " " << why;
    throw InvalidArgument(msg.str());
  }
}

void MissingValueSource::mark(float* v, int64_t count) {
  int64_t found = 0;
  for (int64_t i = 0; i < count; ++i)
    if (v[i] == value_) {
      v[i] = std::numeric_limits<float>::quiet_NaN();
      ++found;
    }
  matches_ += found;
}

void MissingValueSource::readSlab(int64_t z0, int64_t zCount, float* out) {
  inner_.readSlab(z0, zCount, out);
  const Index3 d = dims();
  mark(out, d[0] * d[1] * zCount);
}

void MissingValueSource::readRows(int64_t z0, int64_t zCount, int64_t y0, int64_t yCount,
                                  float* out) {
  inner_.readRows(z0, zCount, y0, yCount, out);
  mark(out, dims()[0] * yCount * zCount);
}

}  // namespace afam
