// SPDX-License-Identifier: BSD-3-Clause
// What a frame draws (Renderer::loadModels): the exact frame waits for every selected block; a
// frame under a miss budget never waits past its deadline, and never reads on its own thread.
#include <algorithm>
#include <chrono>
#include <unordered_set>

#include "afam/base/thread_scratch.hpp"
#include "afam/render/renderer.hpp"

namespace afam {

using Clock = std::chrono::steady_clock;

namespace {

const Payload& noFloats() {
  static const Payload none = std::make_shared<const CachedModel>();
  return none;
}

}  // namespace

bool Renderer::isEmptyBlock(const BlockRef& block) const {
  return file_->entries()[size_t(block.entry)].kind == BlockKind::Empty;
}

double Renderer::keepResidentLevels(FrameStats& st) {
  if (!residentReady_) {
    const auto t0 = Clock::now();
    ResidentLevels kept = residentLevels(*file_, resources_.cache);
    kept.entries = inBox(kept.entries);  // a rank keeps its box's only
    cache_->setKept(kept.entries);       // before they load: they never evict one another
    loader_->request(kept.entries, LruCache::Purpose::Frame);
    loader_->waitFor(kept.entries, Clock::time_point::max());
    residentLevels_ = kept.levels;
    residentReady_ = true;
    st.residentLevels = residentLevels_;
    st.residentLoadMs = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    return st.residentLoadMs;
  }
  st.residentLevels = residentLevels_;
  return 0;
}

BlockRef Renderer::parentOf(const BlockRef& block) const {
  BlockRef up;
  up.level = block.level - 1;
  up.ijk = file_->partition().parent(block.level, block.ijk);
  up.entry = file_->entryIndex(up.level, up.ijk);
  return up;
}

int Renderer::standInLevel(const BlockRef& block) const {
  for (BlockRef up = block; up.level > 0;) {
    up = parentOf(up);
    if (cache_->contains(up.entry) && !cache_->isDamaged(up.entry)) return up.level;
  }
  return -1;
}

bool Renderer::placeStandIn(const BlockRef& block, std::vector<Placement>& placed) {
  for (BlockRef up = block; up.level > 0;) {
    up = parentOf(up);
    if (cache_->isDamaged(up.entry)) continue;  // the next intact ancestor
    if (auto data = cache_->residentHit(up.entry)) {
      placed.push_back(Placement{up, block, std::move(data)});
      return true;
    }
  }
  return false;
}

std::vector<Placement> Renderer::loadModels(const Selection& sel, const Camera& camera,
                                            FrameStats& st, Clock::time_point deadline) {
  const bool budgeted = settings_.missBudgetMs >= 0;
  cache_->setFrameEvictsPinned(!budgeted);
  if (budgeted)  // the first image waits for the resident levels; the budget starts after them
    deadline += std::chrono::microseconds(int64_t(keepResidentLevels(st) * 1e3));
  // Pinned: the frame's blocks and, under a budget, their ancestors (the stand-ins).
  std::unordered_set<int64_t> pins;
  std::vector<BlockRef> missingBlocks;
  const Partition& p = file_->partition();
  for (const BlockRef& b : sel.visible) {
    if (isEmptyBlock(b)) continue;  // nothing to read (drawn as missing)
    pins.insert(b.entry);
    if (!cache_->contains(b.entry) && !cache_->isDamaged(b.entry)) missingBlocks.push_back(b);
    for (BlockRef up = b; budgeted && up.level > 0;) {
      up.ijk = p.parent(up.level, up.ijk);
      up.level--;
      if (!pins.insert(file_->entryIndex(up.level, up.ijk)).second) break;  // and its ancestors
    }
  }
  cache_->setPinned(std::vector<int64_t>(pins.begin(), pins.end()));
  std::vector<int64_t> missing;
  if (budgeted) {  // most important first; earlier frames' requests not started are dropped
    static const std::vector<float> none;
    missing = importanceOrder(
        *file_, camera, missingBlocks, [this](const BlockRef& b) { return standInLevel(b); },
        settings_.blendMode == kBlendComposite ? tf_ : none, tfLo_, tfHi_);
    loader_->requestFrame(missing);
  } else {
    for (const BlockRef& b : missingBlocks) missing.push_back(b.entry);
    loader_->request(missing, LruCache::Purpose::Frame);
  }
  const auto waitStart = Clock::now();
  loader_->waitFor(missing, deadline);
  waitEnd_ = std::min(Clock::now(), deadline);  // the frame's tail starts here
  st.waitMs = std::chrono::duration<double, std::milli>(Clock::now() - waitStart).count();
  std::vector<Placement> placed = placeModels(sel, missing, budgeted, st);
  releaseThreadScratch();  // of a model this thread decoded itself
  return placed;
}

void Renderer::placeOne(const BlockRef& b, Payload data, std::vector<Placement>& placed,
                        FrameStats& st) {
  if (data) {
    placed.push_back(Placement{b, b, std::move(data)});
    return;
  }
  const IntactLoader load = [this](int64_t entry) {
    return cache_->getIntact(entry, LruCache::Purpose::Frame);
  };
  st.damagedBlocks++;
  if (replaceDamaged(*file_, b, load, placed) == 0) st.emptyDamagedBlocks++;
}

std::vector<Placement> Renderer::placeModels(const Selection& sel,
                                             const std::vector<int64_t>& missing, bool budgeted,
                                             FrameStats& st) {
  std::vector<Placement> placed;
  placed.reserve(sel.visible.size());
  const std::unordered_set<int64_t> missed(missing.begin(), missing.end());
  for (const BlockRef& b : sel.visible) {
    if (isEmptyBlock(b)) {
      placed.push_back(Placement{b, b, noFloats()});
      continue;
    }
    // A miss loaded for this frame was counted as one; the frame takes it without a lookup.
    Payload data = missed.count(b.entry) ? cache_->takeLoaded(b.entry) : nullptr;
    if (!budgeted) {  // the exact frame reads what is not resident itself
      placeOne(b, data ? std::move(data) : cache_->getIntact(b.entry, LruCache::Purpose::Frame),
               placed, st);
      continue;
    }
    // Under a budget only what is resident now: nothing is read on the frame's thread (a damaged
    // block's replacement aside, as in the exact frame).
    if (!data && !cache_->isDamaged(b.entry)) data = cache_->residentHit(b.entry);
    if (data || cache_->isDamaged(b.entry)) {
      placeOne(b, std::move(data), placed, st);
      continue;
    }
    st.blocksBehind++;
    st.bytesBehind += file_->entries()[size_t(b.entry)].size;
    if (placeStandIn(b, placed)) st.standInBlocks++;  // else drawn as nothing until it loads
  }
  return placed;
}

}  // namespace afam
