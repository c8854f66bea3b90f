// SPDX-License-Identifier: BSD-3-Clause
#include "afam/volume/volume_source.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <limits>
#include <regex>

#include "afam/base/errors.hpp"
#include "afam/volume/marschner_lobb.hpp"
#include "file_samples.hpp"

namespace afam {

ArraySource::ArraySource(const void* data, SampleType type, Index3 dims, std::string name,
                         std::array<double, 3> origin, std::array<double, 3> spacing)
    : data_(static_cast<const unsigned char*>(data)),
      type_(type),
      dims_(dims),
      name_(std::move(name)),
      origin_(origin),
      spacing_(spacing) {
  if (!data) throw InvalidArgument("ArraySource: null data");
  for (int a = 0; a < 3; ++a)
    if (dims[a] < 1)
      throw InvalidArgument(std::string("ArraySource: axis ") + "xyz"[a] + " has " +
                            std::to_string(dims[a]) + " samples; every axis needs at least 1");
}

void VolumeSource::readRows(int64_t z0, int64_t zCount, int64_t y0, int64_t yCount, float* out) {
  const Index3 d = dims();
  if (y0 == 0 && yCount == d[1]) {
    readSlab(z0, zCount, out);
    return;
  }
  std::vector<float> plane(size_t(d[0] * d[1]));
  for (int64_t z = 0; z < zCount; ++z) {
    readSlab(z0 + z, 1, plane.data());
    std::copy(plane.begin() + y0 * d[0], plane.begin() + (y0 + yCount) * d[0],
              out + z * d[0] * yCount);
  }
}

void ArraySource::readSlab(int64_t z0, int64_t zCount, float* out) {
  readRows(z0, zCount, 0, dims_[1], out);
}

void ArraySource::readRows(int64_t z0, int64_t zCount, int64_t y0, int64_t yCount, float* out) {
  if (z0 < 0 || zCount < 0 || z0 + zCount > dims_[2] || y0 < 0 || yCount < 0 ||
      y0 + yCount > dims_[1])
    throw InvalidArgument("ArraySource: planes [" + std::to_string(z0) + ", " +
                          std::to_string(z0 + zCount) + "), rows [" + std::to_string(y0) + ", " +
                          std::to_string(y0 + yCount) + ") outside the volume");
  const size_t row = size_t(dims_[0]), plane = row * size_t(dims_[1]), rows = row * size_t(yCount);
  const size_t bytes = size_t(sampleTypeSize(type_));
  if (yCount == dims_[1]) {  // whole planes: one run of samples
    samplesToFloat(type_, data_ + size_t(z0) * plane * bytes, uint64_t(zCount) * plane, out);
    return;
  }
  for (int64_t z = 0; z < zCount; ++z)
    samplesToFloat(type_, data_ + (size_t(z0 + z) * plane + size_t(y0) * row) * bytes, rows,
                   out + size_t(z) * rows);
}

bool parseRawName(const std::string& path, Index3& dims, SampleType& type) {
  static const std::regex re(R"(_(\d+)x(\d+)x(\d+)_([a-z0-9]+)\.raw$)");
  std::smatch m;
  if (!std::regex_search(path, m, re)) return false;
  if (!tryParseSampleType(m[4].str(), type)) return false;
  for (int a = 0; a < 3; ++a) {
    // A size the .afam header cannot hold (0, or above 2^31 - 1) is not a volume's name.
    const std::string digits = m[a + 1].str();
    if (digits.size() > 10) return false;
    const long long v = std::stoll(digits);
    if (v < 1 || v > std::numeric_limits<int32_t>::max()) return false;
    dims[a] = v;
  }
  return true;
}

RawFileSource::RawFileSource(const std::string& path, Index3 dims, SampleType type,
                             std::array<double, 3> origin, std::array<double, 3> spacing)
    : path_(path), dims_(dims), type_(type), origin_(origin), spacing_(spacing) {
  for (int a = 0; a < 3; ++a)
    if (dims[a] < 1)
      throw InvalidArgument(path + ": axis " + "xyz"[a] + " has " + std::to_string(dims[a]) +
                            " samples; every axis needs at least 1");
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) throw IoError(path + ": cannot open: " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd_, &st) != 0) throw IoError(path + ": cannot stat: " + std::strerror(errno));
  uint64_t expected = uint64_t(sampleTypeSize(type));
  for (int a = 0; a < 3; ++a)
    if (__builtin_mul_overflow(expected, uint64_t(dims[a]), &expected)) {
      ::close(fd_);
      fd_ = -1;
      throw InvalidArgument(path + ": " + std::to_string(dims[0]) + "x" + std::to_string(dims[1]) +
                            "x" + std::to_string(dims[2]) + " " + sampleTypeName(type) +
                            " is more than 2^64 bytes");
    }
  if (uint64_t(st.st_size) != expected) {
    ::close(fd_);
    fd_ = -1;
    throw InvalidArgument(path + ": file has " + std::to_string(st.st_size) + " bytes, " +
                          std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" +
                          std::to_string(dims[2]) + " " + sampleTypeName(type) + " needs " +
                          std::to_string(expected));
  }
}

RawFileSource::~RawFileSource() {
  if (fd_ >= 0) ::close(fd_);
}

std::string RawFileSource::name() const {
  std::string base =
      path_.substr(path_.find_last_of('/') == std::string::npos ? 0 : path_.find_last_of('/') + 1);
  const size_t us = base.find('_');
  return us == std::string::npos || us == 0 ? base : base.substr(0, us);
}

void VolumeSource::readStoredRows(int64_t, int64_t, int64_t, int64_t, void*) {
  throw Error(name() + ": no samples as stored to read (storedType() is none)");
}

std::optional<SampleType> RawFileSource::storedType() const { return storedAs(type_); }

void RawFileSource::readStoredRows(int64_t z0, int64_t zCount, int64_t y0, int64_t yCount,
                                   void* out) {
  if (!storedType()) return VolumeSource::readStoredRows(z0, zCount, y0, yCount, out);  // throws
  readStoredFileRows(fd_, path_, 0,
                     storedRows(dims_, sampleTypeSize(type_), z0, zCount, y0, yCount, path_), out);
}

std::optional<SampleType> ArraySource::storedType() const { return storedAs(type_); }

void ArraySource::readStoredRows(int64_t z0, int64_t zCount, int64_t y0, int64_t yCount,
                                 void* out) {
  if (!storedType()) return VolumeSource::readStoredRows(z0, zCount, y0, yCount, out);  // throws
  copyStoredRows(
      data_, storedRows(dims_, sampleTypeSize(type_), z0, zCount, y0, yCount, "ArraySource"), out);
}

void RawFileSource::readSlab(int64_t z0, int64_t zCount, float* out) {
  if (z0 < 0 || zCount < 0 || z0 + zCount > dims_[2])
    throw InvalidArgument(path_ + ": planes outside the volume");
  const uint64_t plane = uint64_t(dims_[0]) * uint64_t(dims_[1]);
  readFileSamples(fd_, path_, uint64_t(z0) * plane * uint64_t(sampleTypeSize(type_)), type_,
                  plane * uint64_t(zCount), out);
}

void MarschnerLobbSource::readSlab(int64_t z0, int64_t zCount, float* out) {
  marschnerLobbSlab(MarschnerLobb{}, dims_, z0, zCount, out);
}

}  // namespace afam
