// SPDX-License-Identifier: BSD-3-Clause
#include "afam/format/file_identity.hpp"

#include <sys/stat.h>

namespace afam {

namespace {

FileIdentity fromStat(const struct stat& st) {
  FileIdentity id;
  id.device = static_cast<uint64_t>(st.st_dev);
  id.inode = static_cast<uint64_t>(st.st_ino);
  id.size = static_cast<uint64_t>(st.st_size);
  id.mtimeNs = static_cast<int64_t>(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec;
  id.exists = true;
  return id;
}

}  // namespace

FileIdentity identityOfDescriptor(int fd) {
  struct stat st {};
  return ::fstat(fd, &st) == 0 ? fromStat(st) : FileIdentity{};
}

FileIdentity identityOfPath(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 ? fromStat(st) : FileIdentity{};
}

std::string describeChange(const FileIdentity& opened, const FileIdentity& now) {
  if (!now.exists) return "it no longer exists";
  if (now.device != opened.device || now.inode != opened.inode)
    return "it was replaced by another file";
  if (now.size != opened.size)
    return "its size went from " + std::to_string(opened.size) + " to " + std::to_string(now.size) +
           " bytes";
  if (now.mtimeNs != opened.mtimeNs) return "it was rewritten (its modification time changed)";
  return {};
}

}  // namespace afam
