// SPDX-License-Identifier: BSD-3-Clause
// A run's first step encoded more than once: encodeRun's headroom trial encodes it with and
// without headroom, and the run then encodes it again with each block's choice. A block of the
// first step has no step before, so its stored form follows from its samples, the bound it is
// coded to and whether it searches (its parent's complex flag): kept by those, a block the run
// encodes again is taken instead of fitted, the same bytes. The trial keeps; the run takes.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <tuple>

#include "afam/format/partition.hpp"

namespace afam {

struct BlockTask;  // the encoder's (private to Core)

class FirstStepBlocks {
 public:
  FirstStepBlocks();
  ~FirstStepBlocks();
  FirstStepBlocks(const FirstStepBlocks&) = delete;
  FirstStepBlocks& operator=(const FirstStepBlocks&) = delete;

  /// From now on blocks are taken (each at most once), no longer kept.
  void startTaking();
  int64_t kept() const;
  int64_t taken() const;

  // The encoder's (encodeBlock), from its fitting threads:
  /// Keeps t's stored form, coded to `bound` (while keeping).
  void keep(int level, double bound, const BlockTask& t);
  /// t's stored form, if a block of the same place, bound and search was kept (while taking).
  bool take(int level, double bound, BlockTask& t);

 private:
  using Key = std::tuple<int, int, int, int, double, bool>;  // level, ijk, bound, search
  mutable std::mutex mutex_;
  bool taking_ = false;
  int64_t kept_ = 0, taken_ = 0;
  std::map<Key, std::unique_ptr<BlockTask>> blocks_;
};

}  // namespace afam
