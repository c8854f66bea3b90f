// SPDX-License-Identifier: BSD-3-Clause
#include "afam/render/damage.hpp"

#include <algorithm>

namespace afam {

bool DamageLog::isDamaged(const AfamFile& file, int64_t entry) const {
  const uint64_t key = modelKey(file.entries().at(size_t(entry)));
  std::lock_guard<std::mutex> g(mutex_);
  return damaged_.count(key) != 0;
}

bool DamageLog::record(const AfamFile& file, int64_t entry, const std::string& message) {
  const uint64_t key = modelKey(file.entries().at(size_t(entry)));
  std::lock_guard<std::mutex> g(mutex_);
  if (!damaged_.insert(key).second) return false;
  pending_.push_back(message +
                     "; this micro-model is skipped and its region drawn from the nearest "
                     "intact level (`afam verify " +
                     file.path() + "` lists every damaged micro-model)");
  return true;
}

std::vector<std::string> DamageLog::takeReports() {
  std::lock_guard<std::mutex> g(mutex_);
  std::vector<std::string> out;
  out.swap(pending_);
  return out;
}

size_t DamageLog::count() const {
  std::lock_guard<std::mutex> g(mutex_);
  return damaged_.size();
}

namespace {

/// The block of `level` holding the finest cell `cell` of block (fromLevel, ijk)'s first corner.
BlockRef blockAt(const AfamFile& file, int level, const Int3& firstCell) {
  const int r = file.partition().stride(level);
  BlockRef b;
  b.level = level;
  for (int a = 0; a < 3; ++a) b.ijk[a] = firstCell[a] / r;
  b.entry = file.entryIndex(level, b.ijk);
  return b;
}

int replaceByChildren(const AfamFile& file, const BlockRef& block, const IntactLoader& load,
                      std::vector<Placement>& out) {
  const Partition& p = file.partition();
  if (block.level + 1 >= p.levels()) return 0;
  const int r = p.stride(block.level), rc = p.stride(block.level + 1);
  const Int3 bf = p.blocksPerAxis(p.levels() - 1);
  int lo[3], hi[3];  // children per axis, inclusive
  for (int a = 0; a < 3; ++a) {
    const int c0 = block.ijk[a] * r, c1 = std::min((block.ijk[a] + 1) * r, bf[a]);
    lo[a] = c0 / rc;
    hi[a] = std::max(c0, c1 - 1) / rc;
  }
  int placed = 0;
  for (int z = lo[2]; z <= hi[2]; ++z)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int x = lo[0]; x <= hi[0]; ++x) {
        BlockRef c;
        c.level = block.level + 1;
        c.ijk = Int3{x, y, z};
        c.entry = file.entryIndex(c.level, c.ijk);
        if (c.entry < 0) continue;
        if (auto data = load(c.entry)) {
          out.push_back(Placement{c, c, std::move(data)});
          ++placed;
        } else {
          placed += replaceByChildren(file, c, load, out);
        }
      }
  return placed;
}

}  // namespace

int replaceDamaged(const AfamFile& file, const BlockRef& damaged, const IntactLoader& load,
                   std::vector<Placement>& out) {
  const int r = file.partition().stride(damaged.level);
  const Int3 first{damaged.ijk[0] * r, damaged.ijk[1] * r, damaged.ijk[2] * r};
  for (int level = damaged.level - 1; level >= 0; --level) {
    const BlockRef up = blockAt(file, level, first);
    if (up.entry < 0) continue;
    if (auto data = load(up.entry)) {
      out.push_back(Placement{up, damaged, std::move(data)});
      return 1;
    }
  }
  return replaceByChildren(file, damaged, load, out);
}

}  // namespace afam
