// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>

#include "afam/render/frame_budget.hpp"

namespace afam {

namespace {

/// Whether `used` fits `share` of `limit` (0: unlimited, then of `whole`).
bool fitsShare(uint64_t used, uint64_t limit, uint64_t whole, double share) {
  return double(used) <= share * double(limit ? limit : whole);
}

}  // namespace

ResidentLevels residentLevels(const AfamFile& file, const CacheBudget& budget, double share) {
  const int levels = file.partition().levels();
  std::vector<uint64_t> bytes(size_t(levels), 0), blocks(size_t(levels), 0);
  uint64_t allBytes = 0, allBlocks = 0;
  for (const ModelEntry& e : file.entries()) {
    if (e.kind == BlockKind::Empty || e.level < 0 || e.level >= levels) continue;
    bytes[size_t(e.level)] += e.size;
    blocks[size_t(e.level)]++;
    allBytes += e.size;
    allBlocks++;
  }
  ResidentLevels out;
  uint64_t sumBytes = 0, sumBlocks = 0;
  for (int l = 0; l < levels; ++l) {
    sumBytes += bytes[size_t(l)];
    sumBlocks += blocks[size_t(l)];
    if (!fitsShare(sumBytes, budget.bytes, allBytes, share) ||
        !fitsShare(sumBlocks, budget.blocks, allBlocks, share))
      break;
    out.levels = l + 1;
  }
  // Level 0 whenever it fits half of each budget: a stand-in for every block.
  if (out.levels == 0 && levels > 0 && fitsShare(bytes[0], budget.bytes, allBytes, 0.5) &&
      fitsShare(blocks[0], budget.blocks, allBlocks, 0.5))
    out.levels = 1;
  for (int64_t i = 0; i < int64_t(file.entries().size()); ++i) {
    const ModelEntry& e = file.entries()[size_t(i)];
    if (e.level >= out.levels || e.kind == BlockKind::Empty) continue;
    out.entries.push_back(i);
    out.bytes += e.size;
  }
  std::stable_sort(out.entries.begin(), out.entries.end(), [&](int64_t a, int64_t b) {
    return file.entries()[size_t(a)].level < file.entries()[size_t(b)].level;
  });
  return out;
}

}  // namespace afam
