// SPDX-License-Identifier: BSD-3-Clause
// Noticing that an open file was changed by another process.
//
// An AfamFile reads its index once, at open; a payload read later is only meaningful if the bytes
// on disk are still those the index describes. FileIdentity is what open() records (the file's
// device and inode, size and modification time) and what later reads compare against: the open
// descriptor's size and time tell an in-place rewrite or a truncation, the path's device and inode
// tell a file replaced by rename (as AfamWriter does) or removed.
#pragma once

#include <cstdint>
#include <string>

#include "afam/base/errors.hpp"

namespace afam {

/// The file changed on disk since it was opened; what was read from it before may not match what
/// is there now. Not a FormatError: the file is not damaged, it is another file.
struct FileChangedError : IoError {
  using IoError::IoError;
};

struct FileIdentity {
  uint64_t device = 0, inode = 0, size = 0;
  int64_t mtimeNs = 0;
  bool exists = false;
};

/// The identity of an open descriptor (exists is false if fstat fails).
FileIdentity identityOfDescriptor(int fd);
/// The identity of what a path names now (exists is false if it cannot be stat'ed).
FileIdentity identityOfPath(const std::string& path);

/// Empty when `now` is the file `opened` describes; otherwise what changed, as a clause such as
/// "it was replaced by another file" or "its size went from 1200 to 720 bytes".
std::string describeChange(const FileIdentity& opened, const FileIdentity& now);

}  // namespace afam
