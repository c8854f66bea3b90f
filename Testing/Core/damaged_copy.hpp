// SPDX-License-Identifier: BSD-3-Clause
// Test helper: a copy of an .afam file with 8 bytes inverted inside chosen payloads.
#pragma once

#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/format/afam_file.hpp"

namespace afam_test {

/// A copy of `src` at `path` with 8 bytes inverted in the middle of each listed entry's payload
/// (entries must store at least 8 bytes), opened.
inline std::shared_ptr<const afam::AfamFile> damagedCopy(const afam::AfamFile& src,
                                                         const std::string& path,
                                                         const std::vector<int64_t>& entries) {
  std::ifstream in(src.path(), std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (int64_t i : entries) {
    const afam::ModelEntry& e = src.entries().at(size_t(i));
    if (e.storedSize < 8) throw afam::InvalidArgument("damagedCopy: entry too small to damage");
    const uint64_t at = e.offset + (e.storedSize - 8) / 2;
    for (int k = 0; k < 8; ++k) bytes[at + k] = char(~bytes[at + k]);
  }
  std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  return afam::AfamFile::open(path);
}

}  // namespace afam_test
