// SPDX-License-Identifier: BSD-3-Clause
// The GPU model pool's book-keeping (PoolLedger), which needs no GPU: LRU eviction order, the
// budget never exceeded, no overlapping allocations, re-upload counts against a reference LRU.
#include <gtest/gtest.h>

#include <algorithm>
#include <list>
#include <map>
#include <random>

#include "afam/cuda/common/gpu_error.hpp"
#include "afam/cuda/decode/pool_ledger.hpp"

namespace afam {
namespace {

TEST(PoolLedger, EvictsLeastRecentlyUsedOfEarlierFrames) {
  PoolLedger ledger(4 * 1024, 256);
  ledger.beginFrame();
  for (uint64_t k : {1, 2, 3, 4}) EXPECT_TRUE(ledger.acquire(k, 1024).uploadNeeded);
  ledger.beginFrame();
  EXPECT_FALSE(ledger.acquire(2, 1024).uploadNeeded);  // 2 becomes most recent
  EXPECT_FALSE(ledger.acquire(1, 1024).uploadNeeded);
  ledger.beginFrame();
  EXPECT_TRUE(ledger.acquire(5, 1024).uploadNeeded);  // evicts 3 (oldest), not 1 or 2
  EXPECT_TRUE(ledger.acquire(6, 1024).uploadNeeded);  // evicts 4
  EXPECT_EQ(ledger.evictedThisFrame(), (std::vector<uint64_t>{3, 4}));
  EXPECT_TRUE(ledger.resident(1));
  EXPECT_TRUE(ledger.resident(2));
  EXPECT_FALSE(ledger.resident(3));
  EXPECT_EQ(ledger.stats().evictions, 2u);
  EXPECT_EQ(ledger.stats().uploads, 6u);
  EXPECT_EQ(ledger.stats().hits, 2u);
}

TEST(PoolLedger, TellsTheBytesAModelWasAcquiredWith) {
  PoolLedger ledger(4 * 1024, 256);
  ledger.beginFrame();
  ledger.acquire(1, 1000);  // the requested bytes, not the aligned allocation
  EXPECT_EQ(ledger.residentBytes(1), 1000u);
  EXPECT_EQ(ledger.residentBytes(2), 0u);
  EXPECT_TRUE(ledger.acquire(1, 300).uploadNeeded);  // another size: placed again
  EXPECT_EQ(ledger.residentBytes(1), 300u);
  ledger.forget(1);
  EXPECT_EQ(ledger.residentBytes(1), 0u);
}

TEST(PoolLedger, FrameLargerThanBudgetIsRecoverable) {
  PoolLedger ledger(3 * 1024, 256);
  ledger.beginFrame();
  ledger.acquire(1, 1024);
  ledger.acquire(2, 1024);
  ledger.acquire(3, 1024);
  // All three are pinned by this frame: a fourth cannot fit.
  EXPECT_THROW(ledger.acquire(4, 1024), GpuOutOfMemory);
  EXPECT_THROW(ledger.acquire(9, 8 * 1024), GpuOutOfMemory);  // larger than the whole budget
  // Next frame the same request succeeds by evicting.
  ledger.beginFrame();
  EXPECT_NO_THROW(ledger.acquire(4, 1024));
  EXPECT_LE(ledger.stats().residentBytes, ledger.stats().capacityBytes);
}

TEST(PoolLedger, BudgetNeverExceededAndAllocationsNeverOverlap) {
  const size_t capacity = 1 << 20;
  PoolLedger ledger(capacity, 256);
  std::mt19937 rng(7);
  std::map<uint64_t, std::pair<size_t, size_t>> live;  // key -> (offset, size)
  std::map<uint64_t, size_t> sizeOf;
  for (int frame = 0; frame < 300; ++frame) {
    ledger.beginFrame();
    const int models = 1 + int(rng() % 40);
    size_t seen = 0;  // evictions of this frame already applied to `live`
    for (int i = 0; i < models; ++i) {
      const uint64_t key = rng() % 400;
      if (!sizeOf.count(key)) sizeOf[key] = 1000 + rng() % 20000;
      try {
        const auto place = ledger.acquire(key, sizeOf[key]);
        const auto& evicted = ledger.evictedThisFrame();
        for (; seen < evicted.size(); ++seen) live.erase(evicted[seen]);
        live[key] = {place.offset, (sizeOf[key] + 255) & ~size_t(255)};
      } catch (const GpuOutOfMemory&) {
        // Fragmentation or a too-large frame: allowed, must leave the ledger consistent.
        const auto& evicted = ledger.evictedThisFrame();
        for (; seen < evicted.size(); ++seen) live.erase(evicted[seen]);
      }
      ASSERT_LE(ledger.stats().residentBytes, capacity);
    }
    // Check live allocations against the ledger and for overlap.
    std::vector<std::pair<size_t, size_t>> ranges;
    size_t sum = 0;
    for (auto it = live.begin(); it != live.end();) {
      if (!ledger.resident(it->first)) {
        it = live.erase(it);
        continue;
      }
      ranges.push_back(it->second);
      sum += it->second.second;
      ++it;
    }
    std::sort(ranges.begin(), ranges.end());
    for (size_t r = 1; r < ranges.size(); ++r) {
      ASSERT_LE(ranges[r - 1].first + ranges[r - 1].second, ranges[r].first);
    }
    if (!ranges.empty()) {
      ASSERT_LE(ranges.back().first + ranges.back().second, capacity);
    }
    ASSERT_EQ(sum, ledger.stats().residentBytes);
  }
  EXPECT_LE(ledger.stats().peakResidentBytes, capacity);
  EXPECT_GT(ledger.stats().evictions, 0u);
}

TEST(PoolLedger, UploadCountsMatchReferenceLru) {
  // Equal-size models: the ledger must behave exactly like an ideal LRU of `slots` entries.
  const int slots = 50;
  PoolLedger ledger(size_t(slots) * 4096, 256);
  std::list<uint64_t> reference;  // front = most recent
  uint64_t refUploads = 0, refEvictions = 0;
  std::mt19937 rng(11);
  for (int frame = 0; frame < 200; ++frame) {
    ledger.beginFrame();
    // A moving window of keys, like a camera drifting through a volume.
    const uint64_t base = uint64_t(frame / 3);
    for (int i = 0; i < 30; ++i) {
      const uint64_t key = base + uint64_t(rng() % 40);
      ledger.acquire(key, 4096);
      auto it = std::find(reference.begin(), reference.end(), key);
      if (it != reference.end()) {
        reference.erase(it);
      } else {
        ++refUploads;
        if (int(reference.size()) == slots) {
          reference.pop_back();
          ++refEvictions;
        }
      }
      reference.push_front(key);
    }
  }
  EXPECT_EQ(ledger.stats().uploads, refUploads);
  EXPECT_EQ(ledger.stats().evictions, refEvictions);
  std::printf("reference LRU over 200 frames: %llu uploads, %llu evictions (ledger equal)\n",
              (unsigned long long)refUploads, (unsigned long long)refEvictions);
}

}  // namespace
}  // namespace afam
