// SPDX-License-Identifier: BSD-3-Clause
#include "afam/ranks/same_file.hpp"

#include <algorithm>
#include <sstream>

namespace afam {

namespace {

template <typename T>
uint32_t crcOf(const T& value, uint32_t crc) {
  return crc32(&value, sizeof value, crc);
}

std::string rankList(const std::vector<int>& ranks) {
  std::ostringstream s;
  s << (ranks.size() == 1 ? "rank " : "ranks ");
  for (size_t i = 0; i < ranks.size(); ++i)
    s << (i == 0 ? "" : i + 1 == ranks.size() ? " and " : ", ") << ranks[i];
  return s.str();
}

}  // namespace

uint64_t contentFingerprint(const AfamFile& file) {
  uint32_t crc = crcOf(file.fileSize(), 0);
  for (const int64_t d : file.header().dims) crc = crcOf(d, crc);
  crc = crcOf(file.step(), crc);
  for (const ModelEntry& e : file.entries()) {
    crc = crcOf(e.offset, crc);
    crc = crcOf(e.storedSize, crc);
    crc = crcOf(e.checksum, crc);
  }
  return uint64_t(file.fileSize() & 0xffffffffu) << 32 | crc | 1u;  // never 0
}

std::string ranksFileDisagreement(const std::vector<uint64_t>& fingerprints,
                                  const std::string& path) {
  std::vector<int> missing, other;
  const auto opened =
      std::find_if(fingerprints.begin(), fingerprints.end(), [](uint64_t f) { return f != 0; });
  const uint64_t reference = opened == fingerprints.end() ? 0 : *opened;
  for (size_t r = 0; r < fingerprints.size(); ++r) {
    if (fingerprints[r] == 0)
      missing.push_back(int(r));
    else if (fingerprints[r] != reference)
      other.push_back(int(r));
  }
  if (missing.empty() && other.empty()) return {};
  std::ostringstream s;
  s << "the " << fingerprints.size() << " ranks do not draw one file: ";
  if (!missing.empty()) s << rankList(missing) << " could not open " << path;
  if (!missing.empty() && !other.empty()) s << "; ";
  if (!other.empty())
    s << rankList(other) << " opened another " << path << " than rank "
      << (opened - fingerprints.begin()) << " did";
  s << " (each node must see the same file); the volume is not drawn";
  return s.str();
}

}  // namespace afam
