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

namespace afam {

ArraySource::ArraySource(const float* data, Index3 dims, std::string name, std::array<double, 3> origin,
                         std::array<double, 3> spacing)
    : data_(data), dims_(dims), name_(std::move(name)), origin_(origin), spacing_(spacing) {
  if (!data) throw InvalidArgument("ArraySource: null data");
  for (int a = 0; a < 3; ++a)
    if (dims[a] < 1) throw InvalidArgument("ArraySource: dimensions must be >= 1");
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
    std::copy(plane.begin() + y0 * d[0], plane.begin() + (y0 + yCount) * d[0], out + z * d[0] * yCount);
  }
}

void ArraySource::readSlab(int64_t z0, int64_t zCount, float* out) {
  if (z0 < 0 || zCount < 0 || z0 + zCount > dims_[2])
    throw InvalidArgument("ArraySource: planes [" + std::to_string(z0) + ", " + std::to_string(z0 + zCount) +
                          ") outside the volume");
  const size_t plane = size_t(dims_[0] * dims_[1]);
  std::memcpy(out, data_ + size_t(z0) * plane, size_t(zCount) * plane * sizeof(float));
}

const char* scalarTypeName(ScalarType t) {
  switch (t) {
    case ScalarType::Float32: return "float32";
    case ScalarType::Float64: return "float64";
    case ScalarType::UInt8: return "uint8";
    case ScalarType::UInt16: return "uint16";
    case ScalarType::Int16: return "int16";
  }
  return "unknown";
}

ScalarType parseScalarType(const std::string& s) {
  if (s == "float32" || s == "float") return ScalarType::Float32;
  if (s == "float64" || s == "double") return ScalarType::Float64;
  if (s == "uint8") return ScalarType::UInt8;
  if (s == "uint16") return ScalarType::UInt16;
  if (s == "int16") return ScalarType::Int16;
  throw InvalidArgument("unknown scalar type '" + s + "' (expected float32, float64, uint8, uint16 or int16)");
}

int scalarTypeSize(ScalarType t) {
  switch (t) {
    case ScalarType::Float32: return 4;
    case ScalarType::Float64: return 8;
    case ScalarType::UInt8: return 1;
    case ScalarType::UInt16: return 2;
    case ScalarType::Int16: return 2;
  }
  return 4;
}

bool parseRawName(const std::string& path, Index3& dims, ScalarType& type) {
  static const std::regex re(R"(_(\d+)x(\d+)x(\d+)_(float32|float64|uint8|uint16|int16)\.raw$)");
  std::smatch m;
  if (!std::regex_search(path, m, re)) return false;
  for (int a = 0; a < 3; ++a) {
    // A size the .afam header cannot hold (0, or above 2^31 - 1) is not a volume's name.
    const std::string digits = m[a + 1].str();
    if (digits.size() > 10) return false;
    const long long v = std::stoll(digits);
    if (v < 1 || v > std::numeric_limits<int32_t>::max()) return false;
    dims[a] = v;
  }
  type = parseScalarType(m[4].str());
  return true;
}

RawFileSource::RawFileSource(const std::string& path, Index3 dims, ScalarType type, std::array<double, 3> origin,
                             std::array<double, 3> spacing)
    : path_(path), dims_(dims), type_(type), origin_(origin), spacing_(spacing) {
  for (int a = 0; a < 3; ++a)
    if (dims[a] < 1) throw InvalidArgument(path + ": dimensions must be >= 1");
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) throw IoError(path + ": cannot open: " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd_, &st) != 0) throw IoError(path + ": cannot stat: " + std::strerror(errno));
  uint64_t expected = uint64_t(scalarTypeSize(type));
  for (int a = 0; a < 3; ++a)
    if (__builtin_mul_overflow(expected, uint64_t(dims[a]), &expected)) {
      ::close(fd_);
      fd_ = -1;
      throw InvalidArgument(path + ": " + std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" +
                            std::to_string(dims[2]) + " " + scalarTypeName(type) + " is more than 2^64 bytes");
    }
  if (uint64_t(st.st_size) != expected) {
    ::close(fd_);
    fd_ = -1;
    throw InvalidArgument(path + ": file has " + std::to_string(st.st_size) + " bytes, " +
                          std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" + std::to_string(dims[2]) +
                          " " + scalarTypeName(type) + " needs " + std::to_string(expected));
  }
}

RawFileSource::~RawFileSource() {
  if (fd_ >= 0) ::close(fd_);
}

std::string RawFileSource::name() const {
  std::string base = path_.substr(path_.find_last_of('/') == std::string::npos ? 0 : path_.find_last_of('/') + 1);
  const size_t us = base.find('_');
  return us == std::string::npos || us == 0 ? base : base.substr(0, us);
}

void RawFileSource::readSlab(int64_t z0, int64_t zCount, float* out) {
  if (z0 < 0 || zCount < 0 || z0 + zCount > dims_[2])
    throw InvalidArgument(path_ + ": planes outside the volume");
  const int es = scalarTypeSize(type_);
  const uint64_t count = uint64_t(dims_[0]) * uint64_t(dims_[1]) * uint64_t(zCount);
  const uint64_t bytes = count * uint64_t(es);
  const uint64_t offset = uint64_t(z0) * uint64_t(dims_[0]) * uint64_t(dims_[1]) * uint64_t(es);
  unsigned char* dst;
  if (type_ == ScalarType::Float32) {
    dst = reinterpret_cast<unsigned char*>(out);
  } else {
    buffer_.resize(bytes);
    dst = buffer_.data();
  }
  uint64_t done = 0;
  while (done < bytes) {
    const ssize_t r = ::pread(fd_, dst + done, size_t(std::min<uint64_t>(bytes - done, 1u << 30)), off_t(offset + done));
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) throw IoError(path_ + ": read failed at byte " + std::to_string(offset + done) + ": " +
                              (r == 0 ? std::string("unexpected end of file") : std::string(std::strerror(errno))));
    done += uint64_t(r);
  }
  switch (type_) {
    case ScalarType::Float32: break;
    case ScalarType::Float64:
      for (uint64_t i = 0; i < count; ++i) {
        double v;
        std::memcpy(&v, dst + i * 8, 8);
        out[i] = static_cast<float>(v);
      }
      break;
    case ScalarType::UInt8:
      for (uint64_t i = 0; i < count; ++i) out[i] = float(dst[i]);
      break;
    case ScalarType::UInt16:
      for (uint64_t i = 0; i < count; ++i) {
        uint16_t v;
        std::memcpy(&v, dst + i * 2, 2);
        out[i] = float(v);
      }
      break;
    case ScalarType::Int16:
      for (uint64_t i = 0; i < count; ++i) {
        int16_t v;
        std::memcpy(&v, dst + i * 2, 2);
        out[i] = float(v);
      }
      break;
  }
}

void MarschnerLobbSource::readSlab(int64_t z0, int64_t zCount, float* out) {
  marschnerLobbSlab(MarschnerLobb{}, dims_, z0, zCount, out);
}

}  // namespace afam
