// SPDX-License-Identifier: BSD-3-Clause
#include "afam/cuda/decode/pool_ledger.hpp"

#include <string>

#include "afam/cuda/common/gpu_error.hpp"

namespace afam {

PoolLedger::PoolLedger(size_t capacityBytes, size_t alignment)
    : capacity_(capacityBytes), alignment_(alignment) {
  if (alignment_ == 0 || (alignment_ & (alignment_ - 1)) != 0)
    throw InvalidArgument("PoolLedger: alignment " + std::to_string(alignment) +
                          " is not a power of two");
  capacity_ -= capacity_ % alignment_;
  if (capacity_ > 0) free_[0] = capacity_;
  stats_.capacityBytes = capacity_;
}

void PoolLedger::beginFrame() {
  ++frame_;
  ++stats_.frames;
  evictedThisFrame_.clear();
}

void PoolLedger::clear() {
  entries_.clear();
  lru_.clear();
  free_.clear();
  if (capacity_ > 0) free_[0] = capacity_;
  stats_.residentBytes = 0;
  stats_.residentModels = 0;
}

size_t PoolLedger::largestFreeRun() const {
  size_t best = 0;
  for (const auto& run : free_) best = run.second > best ? run.second : best;
  return best;
}

bool PoolLedger::allocate(size_t size, size_t* offset) {
  // Best fit keeps large runs for large models.
  auto best = free_.end();
  for (auto it = free_.begin(); it != free_.end(); ++it)
    if (it->second >= size && (best == free_.end() || it->second < best->second)) best = it;
  if (best == free_.end()) return false;
  *offset = best->first;
  const size_t rest = best->second - size;
  const size_t restOffset = best->first + size;
  free_.erase(best);
  if (rest > 0) free_[restOffset] = rest;
  return true;
}

void PoolLedger::release(size_t offset, size_t size) {
  auto next = free_.lower_bound(offset);
  if (next != free_.end() && offset + size == next->first) {
    size += next->second;
    next = free_.erase(next);
  }
  if (next != free_.begin()) {
    auto prev = std::prev(next);
    if (prev->first + prev->second == offset) {
      prev->second += size;
      return;
    }
  }
  free_[offset] = size;
}

void PoolLedger::forget(uint64_t key) {
  const auto it = entries_.find(key);
  if (it == entries_.end()) return;
  release(it->second.offset, it->second.size);
  stats_.residentBytes -= it->second.size;
  --stats_.residentModels;
  lru_.erase(it->second.lru);
  entries_.erase(it);
}

bool PoolLedger::evictOldest() {
  if (lru_.empty()) return false;
  const uint64_t key = lru_.back();
  auto it = entries_.find(key);
  if (it->second.lastFrame == frame_) return false;  // everything left is pinned by this frame
  release(it->second.offset, it->second.size);
  stats_.residentBytes -= it->second.size;
  --stats_.residentModels;
  ++stats_.evictions;
  evictedThisFrame_.push_back(key);
  lru_.pop_back();
  entries_.erase(it);
  return true;
}

PoolLedger::Placement PoolLedger::acquire(uint64_t key, size_t bytes) {
  const size_t size = ((bytes + alignment_ - 1) / alignment_) * alignment_;
  auto it = entries_.find(key);
  if (it != entries_.end()) {
    if (it->second.rawBytes == bytes) {
      it->second.lastFrame = frame_;
      lru_.splice(lru_.begin(), lru_, it->second.lru);
      ++stats_.hits;
      return {it->second.offset, false};
    }
    // Same key, other size: the model changed; drop the old copy.
    release(it->second.offset, it->second.size);
    stats_.residentBytes -= it->second.size;
    --stats_.residentModels;
    lru_.erase(it->second.lru);
    entries_.erase(it);
  }
  if (size > capacity_)
    throw GpuOutOfMemory("GPU model pool: model " + std::to_string(key) + " needs " +
                             std::to_string(bytes) + " bytes, more than the pool's budget of " +
                             std::to_string(capacity_) + " bytes",
                         "pool_ledger.cpp", __LINE__, "PoolBudgetExceeded", 0);
  size_t offset = 0;
  while (!allocate(size, &offset)) {
    if (!evictOldest())
      throw GpuOutOfMemory(
          "GPU model pool: this frame's models do not fit in the budget of " +
              std::to_string(capacity_) + " bytes (" + std::to_string(stats_.residentBytes) +
              " bytes pinned by this frame, model " + std::to_string(key) + " needs " +
              std::to_string(size) + "); raise the GPU budget, lower the level of detail or " +
              "render on the CPU",
          "pool_ledger.cpp", __LINE__, "PoolBudgetExceeded", 0);
  }
  lru_.push_front(key);
  Entry entry;
  entry.offset = offset;
  entry.size = size;
  entry.rawBytes = bytes;
  entry.lastFrame = frame_;
  entry.lru = lru_.begin();
  entries_.emplace(key, entry);
  stats_.residentBytes += size;
  ++stats_.residentModels;
  if (stats_.residentBytes > stats_.peakResidentBytes)
    stats_.peakResidentBytes = stats_.residentBytes;
  ++stats_.uploads;
  stats_.bytesUploaded += bytes;
  return {offset, true};
}

}  // namespace afam
