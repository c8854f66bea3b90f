// SPDX-License-Identifier: BSD-3-Clause
#include "afam/format/temporary_file.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "afam/base/errors.hpp"

namespace afam {
namespace {

constexpr const char* kSuffix = ".tmp-";
constexpr size_t kRandomChars = 6;  // mkstemp's XXXXXX

void splitPath(const std::string& path, std::string& dir, std::string& base) {
  const size_t slash = path.find_last_of('/');
  dir = slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
  base = slash == std::string::npos ? path : path.substr(slash + 1);
}

bool isOwnPattern(const std::string& name, const std::string& prefix) {
  if (name.size() != prefix.size() + kRandomChars || name.compare(0, prefix.size(), prefix) != 0)
    return false;
  for (size_t i = prefix.size(); i < name.size(); ++i)
    if (!std::isalnum(static_cast<unsigned char>(name[i]))) return false;
  return true;
}

bool sameFile(const struct stat& a, const struct stat& b) {
  return a.st_dev == b.st_dev && a.st_ino == b.st_ino;
}

// Removes `file` if it is a regular file of ours whose lock is free. The lock is held while
// checking that the name still refers to the file opened, so a writer that just created it (and
// has not locked it yet) notices the removal and makes another (createLockedTemporary).
bool removeIfStale(const std::string& file) {
  const int fd = ::open(file.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) return false;
  bool removed = false;
  struct stat opened {
  }, named{};
  if (::fstat(fd, &opened) == 0 && S_ISREG(opened.st_mode) && opened.st_uid == ::geteuid() &&
      ::flock(fd, LOCK_EX | LOCK_NB) == 0 && ::lstat(file.c_str(), &named) == 0 &&
      sameFile(opened, named))
    removed = ::unlink(file.c_str()) == 0;
  ::close(fd);  // releases the lock
  return removed;
}

}  // namespace

int createLockedTemporary(const std::string& path, std::string& tmpPath) {
  const std::string tmpl = path + kSuffix + std::string(kRandomChars, 'X');
  for (int attempt = 0; attempt < 16; ++attempt) {
    std::vector<char> buf(tmpl.begin(), tmpl.end());
    buf.push_back('\0');
    const int fd = ::mkostemp(buf.data(), O_CLOEXEC);
    if (fd < 0)
      throw IoError(path + ": cannot create temporary file " + tmpl + ": " + std::strerror(errno));
    struct stat opened {
    }, named{};
    // Between mkostemp and flock another writer may have judged the file stale and removed it:
    // then the name no longer refers to this descriptor, and we start again.
    if (::flock(fd, LOCK_EX | LOCK_NB) == 0 && ::fstat(fd, &opened) == 0 &&
        ::lstat(buf.data(), &named) == 0 && sameFile(opened, named)) {
      ::fchmod(fd, 0644);
      tmpPath = buf.data();
      return fd;
    }
    ::close(fd);
  }
  throw IoError(path + ": cannot create and lock a temporary file " + tmpl);
}

int removeStaleTemporaries(const std::string& path) {
  std::string dir, base;
  splitPath(path, dir, base);
  const std::string prefix = base + kSuffix;
  DIR* d = ::opendir(dir.c_str());
  if (!d) return 0;
  std::vector<std::string> candidates;
  while (const dirent* e = ::readdir(d))
    if (isOwnPattern(e->d_name, prefix)) candidates.push_back(dir + "/" + e->d_name);
  ::closedir(d);
  int removed = 0;
  for (const std::string& file : candidates) removed += removeIfStale(file) ? 1 : 0;
  return removed;
}

}  // namespace afam
