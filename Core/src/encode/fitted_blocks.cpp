// SPDX-License-Identifier: BSD-3-Clause
#include "fitted_blocks.hpp"

#include <cstring>
#include <type_traits>

#include "afam/base/errors.hpp"

namespace afam {

namespace {

/// The fixed part of a record; entry.storedSize stored bytes follow it.
struct FittedBlockRecord {
  ModelEntry entry;
  int64_t fits;
  double rmse, maxError;
  int32_t ncpStar;
  uint8_t search, complex, exact, reducedDegree;
};
static_assert(std::is_trivially_copyable<FittedBlockRecord>::value, "records are copied as bytes");

}  // namespace

void appendFittedBlock(const BlockTask& t, std::vector<uint8_t>& out) {
  FittedBlockRecord r{};
  r.entry = t.entry;
  r.fits = t.fits;
  r.rmse = t.rmse;
  r.maxError = t.maxError;
  r.ncpStar = t.ncpStar;
  r.search = t.search;
  r.complex = t.complex;
  r.exact = t.exact;
  r.reducedDegree = t.reducedDegree;
  const size_t at = out.size();
  out.resize(at + sizeof r + t.stored.size());
  std::memcpy(out.data() + at, &r, sizeof r);
  if (!t.stored.empty()) std::memcpy(out.data() + at + sizeof r, t.stored.data(), t.stored.size());
}

void readFittedBlocks(const std::vector<uint8_t>& in, std::vector<BlockTask>& out) {
  for (size_t at = 0; at < in.size();) {
    FittedBlockRecord r{};
    if (in.size() - at < sizeof r) throw FormatError("fitted blocks: a record is cut short");
    std::memcpy(&r, in.data() + at, sizeof r);
    at += sizeof r;
    if (in.size() - at < r.entry.storedSize)
      throw FormatError("fitted blocks: a payload is cut short");
    BlockTask t;
    t.ijk = r.entry.block;
    t.entry = r.entry;
    t.fits = r.fits;
    t.rmse = r.rmse;
    t.maxError = r.maxError;
    t.ncpStar = r.ncpStar;
    t.search = r.search != 0;
    t.complex = r.complex != 0;
    t.exact = r.exact != 0;
    t.reducedDegree = r.reducedDegree != 0;
    t.stored.assign(in.begin() + std::ptrdiff_t(at),
                    in.begin() + std::ptrdiff_t(at + r.entry.storedSize));
    at += r.entry.storedSize;
    out.push_back(std::move(t));
  }
}

}  // namespace afam
