// SPDX-License-Identifier: BSD-3-Clause
// A raw volume written by a command (ml, enlarge, decode): bytes go to OUT.tmp, which commit()
// flushes and renames onto OUT; a command that fails (or an exception) leaves no file behind.
#pragma once

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

#include "afam/base/errors.hpp"

namespace afam::cli {

class RawOutput {
 public:
  explicit RawOutput(std::string path) : path_(std::move(path)), tmp_(path_ + ".tmp") {
    fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd_ < 0) throw IoError(tmp_ + ": cannot create: " + std::strerror(errno));
  }
  ~RawOutput() {
    if (fd_ >= 0) ::close(fd_);
    if (!committed_) ::unlink(tmp_.c_str());
  }
  RawOutput(const RawOutput&) = delete;
  RawOutput& operator=(const RawOutput&) = delete;

  /// Writes `bytes` at byte `offset` of the file.
  void writeAt(const void* data, size_t bytes, uint64_t offset) {
    const char* p = static_cast<const char*>(data);
    for (size_t done = 0; done < bytes;) {
      const ssize_t w = ::pwrite(fd_, p + done, bytes - done, off_t(offset + done));
      if (w < 0 && errno == EINTR) continue;
      if (w <= 0) throw IoError(tmp_ + ": write failed: " + std::strerror(errno));
      done += size_t(w);
    }
  }
  /// Writes `bytes` after what was appended before.
  void append(const void* data, size_t bytes) {
    writeAt(data, bytes, end_);
    end_ += bytes;
  }
  /// fsync, close, rename onto the path.
  void commit() {
    const int fd = fd_;
    fd_ = -1;
    if (::fsync(fd) != 0 || ::close(fd) != 0)
      throw IoError(tmp_ + ": cannot flush: " + std::strerror(errno));
    if (::rename(tmp_.c_str(), path_.c_str()) != 0)
      throw IoError(path_ + ": cannot rename: " + std::strerror(errno));
    committed_ = true;
  }

 private:
  std::string path_, tmp_;
  int fd_ = -1;
  uint64_t end_ = 0;
  bool committed_ = false;
};

}  // namespace afam::cli
