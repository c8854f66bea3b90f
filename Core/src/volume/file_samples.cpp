// SPDX-License-Identifier: BSD-3-Clause
#include "file_samples.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <vector>

#include "afam/base/errors.hpp"

namespace afam {

namespace {

/// Bytes a read stages before converting them: a few megabytes, so that the conversion reads
/// them from cache and each reading thread holds no more.
constexpr uint64_t kStagingBytes = uint64_t(4) << 20;

}  // namespace

void readFully(int fd, const std::string& path, uint64_t offset, unsigned char* dst,
               uint64_t bytes) {
  uint64_t done = 0;
  while (done < bytes) {
    const ssize_t r = ::pread(fd, dst + done, size_t(std::min<uint64_t>(bytes - done, 1u << 30)),
                              off_t(offset + done));
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0)
      throw IoError(
          path + ": read failed at byte " + std::to_string(offset + done) + ": " +
          (r == 0 ? std::string("unexpected end of file") : std::string(std::strerror(errno))));
    done += uint64_t(r);
  }
}

void readFileSamples(int fd, const std::string& path, uint64_t offset, SampleType type,
                     uint64_t count, float* out, bool swapBytes) {
  const uint64_t es = uint64_t(sampleTypeSize(type));
  if (type == SampleType::Float32 && !swapBytes) {
    readFully(fd, path, offset, reinterpret_cast<unsigned char*>(out), count * es);
    return;
  }
  thread_local std::vector<unsigned char> staged;
  const uint64_t step = std::max<uint64_t>(1, kStagingBytes / es);  // samples a read
  if (staged.size() < std::min(count, step) * es) staged.resize(std::min(count, step) * es);
  for (uint64_t i = 0; i < count; i += step) {
    const uint64_t n = std::min(step, count - i);
    readFully(fd, path, offset + i * es, staged.data(), n * es);
    samplesToFloat(type, staged.data(), n, out + i, swapBytes);
  }
}

std::optional<SampleType> storedAs(SampleType type) {
  if (type == SampleType::Int8 || type == SampleType::UInt8 || type == SampleType::Int16 ||
      type == SampleType::UInt16)
    return type;
  return std::nullopt;
}

StoredRows storedRows(const Index3& dims, int es, int64_t z0, int64_t zCount, int64_t y0,
                      int64_t yCount, const std::string& what) {
  if (z0 < 0 || zCount < 0 || z0 + zCount > dims[2] || y0 < 0 || yCount < 0 ||
      y0 + yCount > dims[1])
    throw InvalidArgument(what + ": planes [" + std::to_string(z0) + ", " +
                          std::to_string(z0 + zCount) + "), rows [" + std::to_string(y0) + ", " +
                          std::to_string(y0 + yCount) + ") outside the volume");
  const uint64_t row = uint64_t(dims[0]) * uint64_t(es), plane = row * uint64_t(dims[1]);
  if (yCount == dims[1]) return {uint64_t(z0) * plane, plane * uint64_t(zCount), 0, 1};
  return {uint64_t(z0) * plane + uint64_t(y0) * row, row * uint64_t(yCount), plane, zCount};
}

void readStoredFileRows(int fd, const std::string& path, uint64_t base, const StoredRows& rows,
                        void* out) {
  auto* dst = static_cast<unsigned char*>(out);
  for (int64_t z = 0; z < rows.planes; ++z)
    readFully(fd, path, base + rows.first + uint64_t(z) * rows.stride, dst + uint64_t(z) * rows.run,
              rows.run);
}

void copyStoredRows(const unsigned char* volume, const StoredRows& rows, void* out) {
  auto* dst = static_cast<unsigned char*>(out);
  for (int64_t z = 0; z < rows.planes; ++z)
    std::memcpy(dst + uint64_t(z) * rows.run, volume + rows.first + uint64_t(z) * rows.stride,
                rows.run);
}

}  // namespace afam
