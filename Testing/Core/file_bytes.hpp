// SPDX-License-Identifier: BSD-3-Clause
// Test helper: a whole file's bytes, read and written back (to damage copies of .afam files).
#pragma once

#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace afam_test {

inline std::vector<char> readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<char>(std::istreambuf_iterator<char>(in), {});
}

inline void writeAll(const std::string& path, const std::vector<char>& b) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(b.data(), std::streamsize(b.size()));
}

}  // namespace afam_test
