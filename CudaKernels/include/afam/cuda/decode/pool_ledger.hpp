// SPDX-License-Identifier: BSD-3-Clause
// Book-keeping of the GPU model pool, apart from CUDA so it is unit-tested anywhere: which model
// (by 64-bit key) sits at which byte offset of one device arena, least-recently-used eviction under
// the arena's byte budget, and counts. A model used in the current frame is never evicted; when a
// frame's models do not fit together, acquire() throws GpuOutOfMemory (recoverable).
#pragma once

#include <cstddef>
#include <cstdint>
#include <iterator>
#include <list>
#include <map>
#include <unordered_map>
#include <vector>

namespace afam {

struct PoolStats {
  uint64_t frames = 0;
  uint64_t hits = 0;     ///< acquire() of a model already resident
  uint64_t uploads = 0;  ///< acquire() that needs the model's bytes copied to the device
  uint64_t evictions = 0;
  uint64_t bytesUploaded = 0;
  size_t residentBytes = 0;      ///< sum of resident allocations (aligned sizes)
  size_t peakResidentBytes = 0;  ///< never above capacity
  size_t residentModels = 0;
  size_t capacityBytes = 0;
};

class PoolLedger {
 public:
  struct Placement {
    size_t offset = 0;  ///< byte offset in the arena, a multiple of the alignment
    bool uploadNeeded = false;
  };

  /// capacityBytes: the arena's size (the byte budget); alignment: a power of two.
  explicit PoolLedger(size_t capacityBytes, size_t alignment = 256);

  /// Starts a frame: models acquired from now on are pinned until the next beginFrame().
  void beginFrame();
  /// Where model `key` of `bytes` bytes lives; allocates (evicting LRU models of earlier frames)
  /// when it is not resident or its size changed. Throws GpuOutOfMemory when it cannot fit.
  Placement acquire(uint64_t key, size_t bytes);
  /// Drops every model (e.g. the data set changed).
  void clear();
  /// Drops model `key` if it is resident (its bytes turned out unusable, e.g. did not decode).
  void forget(uint64_t key);

  bool resident(uint64_t key) const { return entries_.count(key) != 0; }
  /// The bytes model `key` was acquired with, 0 when it is not resident.
  size_t residentBytes(uint64_t key) const {
    const auto it = entries_.find(key);
    return it == entries_.end() ? 0 : it->second.rawBytes;
  }
  const PoolStats& stats() const { return stats_; }
  /// Keys evicted since the last beginFrame(), oldest first (for tests and logging).
  const std::vector<uint64_t>& evictedThisFrame() const { return evictedThisFrame_; }
  /// Largest free run, in bytes (fragmentation diagnostics).
  size_t largestFreeRun() const;

 private:
  struct Entry {
    size_t offset = 0;
    size_t size = 0;      // aligned size
    size_t rawBytes = 0;  // requested size
    uint64_t lastFrame = 0;
    std::list<uint64_t>::iterator lru;
  };
  bool allocate(size_t size, size_t* offset);
  void release(size_t offset, size_t size);
  bool evictOldest();

  size_t capacity_;
  size_t alignment_;
  uint64_t frame_ = 0;
  std::unordered_map<uint64_t, Entry> entries_;
  std::list<uint64_t> lru_;        // front: most recently used
  std::map<size_t, size_t> free_;  // offset -> size, coalesced
  std::vector<uint64_t> evictedThisFrame_;
  PoolStats stats_;
};

}  // namespace afam
