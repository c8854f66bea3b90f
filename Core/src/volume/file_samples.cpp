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

}  // namespace afam
