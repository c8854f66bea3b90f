// SPDX-License-Identifier: BSD-3-Clause
// Damaged micro-models: a payload whose checksum fails (or that does not decode) is never drawn.
//
// DamageLog remembers, for one file (every step of a run), the models found damaged, by their
// modelKey: each is read once, reported once (one sentence naming the file, the level and the
// block) and then skipped by frame loads and prefetching alike. Thread-safe (the frame thread and
// the load threads both record).
//
// replaceDamaged() decides what is drawn in a damaged block's region instead, the same for every
// ray caster because it runs while the frame is prepared: the nearest intact coarser model (its
// ancestor in the octree, drawn only over the damaged block's cells); when every ancestor is
// damaged too (or the block is at level 0), its children at the next finer level, each intact one
// drawn over its own cells and each damaged one replaced the same way; a finest damaged block with
// no intact ancestor is left empty.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_set>
#include <vector>

#include "afam/format/afam_file.hpp"
#include "afam/render/cached_model.hpp"
#include "afam/scene/lod.hpp"

namespace afam {

class DamageLog {
 public:
  /// Whether the model of the entry (of `file`, a step of the run the log is for) is damaged.
  bool isDamaged(const AfamFile& file, int64_t entry) const;
  /// Records the entry's model as damaged with the reader's message. Returns true the first time
  /// only; the report (message plus what is drawn instead and how to list every damaged block)
  /// is queued for takeReports().
  bool record(const AfamFile& file, int64_t entry, const std::string& message);
  /// Reports not yet handed out, oldest first; each report is handed out once.
  std::vector<std::string> takeReports();
  size_t count() const;

 private:
  mutable std::mutex mutex_;
  std::unordered_set<uint64_t> damaged_;  ///< model keys
  std::vector<std::string> pending_;
};

/// One model of a frame and the block whose finest cells it covers (the same block unless the
/// model stands in for a damaged one).
struct Placement {
  BlockRef model;
  BlockRef region;
  Payload data;
};

/// Loads an entry's payload; returns null when the entry is damaged.
using IntactLoader = std::function<Payload(int64_t entry)>;

/// Appends to `out` what covers the region of the damaged block `damaged` (see above). Returns the
/// number of placements appended (0: the region stays empty).
int replaceDamaged(const AfamFile& file, const BlockRef& damaged, const IntactLoader& load,
                   std::vector<Placement>& out);

}  // namespace afam
