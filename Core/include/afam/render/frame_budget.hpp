// SPDX-License-Identifier: BSD-3-Clause
// What lets a frame keep its miss budget (FrameSettings::missBudgetMs) without drawing holes:
//
// Resident levels: the coarsest levels, as many as fit kResidentShare of the cache's byte and
// block budgets (of the file's decoded models, and of its blocks, where a budget is unlimited),
// are loaded before the first image and never evicted (LruCache::setKept), so that every block
// has a resident ancestor to stand in for it while it loads. Level 0 is kept whenever it fits half
// of each budget, however small the share.
//
// Load order: a frame's misses are loaded most important first, importance being what a block
// adds to the image: its size on the screen (angular size seen from the eye), its nearness to the
// view's centre, its highest opacity under the transfer function, and the levels of detail it
// adds over the model standing in for it.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "afam/format/afam_file.hpp"
#include "afam/render/cache.hpp"
#include "afam/scene/camera.hpp"
#include "afam/scene/lod.hpp"

namespace afam {

/// Share of each cache budget the resident levels may take.
constexpr double kResidentShare = 1.0 / 16;

struct ResidentLevels {
  int levels = 0;                ///< levels 0 .. levels-1 stay resident
  std::vector<int64_t> entries;  ///< their entries that hold a model (not Empty), coarsest first
  uint64_t bytes = 0;            ///< their decoded float32 bytes (an upper bound of what is kept)
};

/// The levels to keep resident in a cache with `budget` (see above).
ResidentLevels residentLevels(const AfamFile& file, const CacheBudget& budget,
                              double share = kResidentShare);

/// What drawing `block` instead of a stand-in `levelsAdded` levels coarser adds to the image
/// (> 0 unless the block is fully transparent or adds no level). `tf` empty: every block opaque.
double blockImportance(const AfamFile& file, const Camera& camera, const BlockRef& block,
                       int levelsAdded, const std::vector<float>& tf, double tfLo, double tfHi);

/// The entries of `blocks`, most important first (ties in the given order). standInLevel(b):
/// the level of the model that stands in for b while it loads (-1: none, which counts as one level
/// coarser than level 0).
std::vector<int64_t> importanceOrder(const AfamFile& file, const Camera& camera,
                                     const std::vector<BlockRef>& blocks,
                                     const std::function<int(const BlockRef&)>& standInLevel,
                                     const std::vector<float>& tf, double tfLo, double tfHi);

}  // namespace afam
