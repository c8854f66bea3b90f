// SPDX-License-Identifier: BSD-3-Clause
// Where a test process writes its temporary files: one folder per process, made on first use
// under $TMPDIR (else /tmp) as afam-test-XXXXXX, and removed with everything in it when the
// process exits. ctest runs each test in its own process, so a green run leaves nothing behind.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace afam_test {

class ScratchDir {
 public:
  ScratchDir() {
    const char* env = std::getenv("TMPDIR");
    std::string tmpl = std::string(env && *env ? env : "/tmp") + "/afam-test-XXXXXX";
    std::vector<char> buf(tmpl.begin(), tmpl.end());
    buf.push_back('\0');
    if (!::mkdtemp(buf.data())) throw std::runtime_error("cannot create a scratch folder " + tmpl);
    path_ = buf.data();
  }
  ~ScratchDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

/// This process's scratch folder (created on first call, removed at exit).
inline const std::string& scratchDir() {
  static const ScratchDir dir;
  return dir.path();
}

/// A path inside scratchDir().
inline std::string scratchPath(const std::string& name) { return scratchDir() + "/" + name; }

}  // namespace afam_test
