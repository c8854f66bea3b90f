// SPDX-License-Identifier: BSD-3-Clause
#include "afam/render/cache.hpp"

#include <fcntl.h>

#include <algorithm>

#include <thread>

#include "afam/base/errors.hpp"
#include "afam/base/thread_scratch.hpp"

namespace afam {

using Clock = std::chrono::steady_clock;

LruCache::LruCache(std::shared_ptr<const AfamFile> file, CacheBudget budget,
                   std::shared_ptr<DamageLog> damage)
    : file_(std::move(file)),
      budget_(budget),
      damage_(damage ? std::move(damage) : std::make_shared<DamageLog>()) {
  if (!file_) throw InvalidArgument("cache: no file");
}

void LruCache::setBandwidthCap(double bytesPerSecond) {
  if (bytesPerSecond < 0) throw InvalidArgument("cache: bandwidth cap must be >= 0");
  std::lock_guard<std::mutex> g(deviceMutex_);
  capBytesPerSecond_ = bytesPerSecond;
}

void LruCache::dropOsCache() const {
#if defined(POSIX_FADV_DONTNEED)
  (void)::posix_fadvise(current()->nativeHandle(), 0, 0, POSIX_FADV_DONTNEED);
#endif
}

void LruCache::throttle(uint64_t bytes, Clock::time_point readStart) {
  Clock::time_point until;
  {
    std::lock_guard<std::mutex> g(deviceMutex_);
    if (capBytesPerSecond_ <= 0) return;
    const auto busy = std::chrono::duration_cast<Clock::duration>(
        std::chrono::duration<double>(double(bytes) / capBytesPerSecond_));
    const Clock::time_point start = std::max(readStart, deviceFree_);
    deviceFree_ = start + busy;
    until = deviceFree_;
  }
  const auto now = Clock::now();
  if (until > now) {
    std::this_thread::sleep_until(until);
    std::lock_guard<std::mutex> g(mutex_);
    stats_.throttleSeconds += std::chrono::duration<double>(until - now).count();
  }
}

LruCache::FilePtr LruCache::current() const {
  std::lock_guard<std::mutex> g(mutex_);
  return file_;
}

void LruCache::setFile(std::shared_ptr<const AfamFile> step) {
  if (!step) throw InvalidArgument("cache: no file");
  const FilePtr now = current();
  // Steps of one run on disk: the same file (device and inode: payloads committed to it are never
  // moved or rewritten, so a model key means the same model in both) and the same partition.
  if (step->path() != now->path() || step->identity().device != now->identity().device ||
      step->identity().inode != now->identity().inode ||
      step->entries().size() != now->entries().size() || step->header().dims != now->header().dims)
    throw InvalidArgument("cache: " + step->path() + " (step " + std::to_string(step->step()) +
                          ") is not a step of " + now->path());
  std::lock_guard<std::mutex> g(mutex_);
  file_ = std::move(step);
  pinned_.clear();
}

Payload LruCache::residentModelBefore(const AfamFile& f, int64_t entry) {
  const ModelEntry& e = f.entries()[size_t(entry)];
  if (!e.residual) return nullptr;
  const std::vector<PayloadPart>& chain = f.chain(entry);
  if (chain.size() < 2) return nullptr;
  std::lock_guard<std::mutex> g(mutex_);
  const auto it = map_.find(chain[chain.size() - 2].offset);  // the model key of the step before
  return it == map_.end() ? nullptr : it->second.data;
}

void LruCache::setCompactForm(bool on) {
  std::lock_guard<std::mutex> g(mutex_);
  compactForm_ = on;
}

void LruCache::setStoredForm(StoredForm form) {
  std::lock_guard<std::mutex> g(mutex_);
  storedForm_ = form;
}

Payload LruCache::load(const AfamFile& f, int64_t entry) {
  const ModelEntry& e = f.entries().at(size_t(entry));
  StoredForm form;
  bool compactForm;
  {
    std::lock_guard<std::mutex> g(mutex_);
    form = storedForm_;
    compactForm = compactForm_;
  }
  const bool stored = form && e.kind != BlockKind::Empty && !e.residual && form(e);
  const bool compact = compactForm && !stored && !e.residual;
  auto data = std::make_shared<CachedModel>(stored || compact ? 0 : e.size / sizeof(float));
  if (e.kind == BlockKind::Empty) return data;  // no valid sample: no payload, nothing to read
  std::function<void(const AfamFile&, int64_t)> hook;
  {
    std::lock_guard<std::mutex> g(mutex_);
    hook = loadHook_;
  }
  if (hook) hook(f, entry);
  const auto t0 = Clock::now();
  // A residual whose model at the step before is resident costs one payload, not its chain.
  Payload before = stored || compact ? nullptr : residentModelBefore(f, entry);
  if (before && !before->hasFloats()) before = nullptr;  // no floats to add to
  try {
    if (stored)
      data->stored = f.readStored(entry);
    else if (compact)
      data->compact = f.readCompact(entry, kCompactShare, *data);
    else
      f.readPayloadOnto(entry, before ? before->data() : nullptr, data->data());
  } catch (const FormatError& ex) {
    damage_->record(f, entry, ex.what());
    throw;
  }
  throttle(e.size, t0);  // the model's bytes, in either form (the cap and the stats)
  const double s = std::chrono::duration<double>(Clock::now() - t0).count();
  std::lock_guard<std::mutex> g(mutex_);
  stats_.bytesRead += e.size;
  stats_.blocksRead++;
  stats_.residualsOnResident += before ? 1 : 0;
  stats_.readSeconds += s;
  return data;
}

bool LruCache::makeRoom(uint64_t bytes, bool mayEvictPinned) {
  auto fits = [&] {
    return (budget_.bytes == 0 ||
            resident_ + reserved_ + threadScratchBytes() + bytes <= budget_.bytes) &&
           (budget_.blocks == 0 || map_.size() + 1 <= budget_.blocks);
  };
  if (budget_.bytes != 0 && bytes > budget_.bytes) return false;
  for (int pass = 0; pass < (mayEvictPinned ? 2 : 1) && !fits(); ++pass) {
    // Walk from the least recently used end; pass 0 skips pinned blocks.
    auto it = lru_.end();
    while (!fits() && it != lru_.begin()) {
      --it;
      const uint64_t key = *it;
      if (kept_.count(key) || (pass == 0 && pinned_.count(key))) continue;
      auto node = map_.find(key);
      resident_ -= node->second.bytes;
      map_.erase(node);
      it = lru_.erase(it);
      stats_.evictions++;
    }
  }
  return fits();
}

Payload LruCache::get(int64_t entry, Purpose purpose, bool* wasHit) {
  return getFrom(current(), entry, purpose, wasHit);
}

Payload LruCache::getFrom(const FilePtr& f, int64_t entry, Purpose purpose, bool* wasHit) {
  const uint64_t key = modelKey(f->entries().at(size_t(entry)));
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    auto it = map_.find(key);
    if (it != map_.end()) {
      if (purpose == Purpose::Frame) {
        stats_.hits++;
        lru_.splice(lru_.begin(), lru_, it->second.pos);
      }
      if (wasHit) *wasHit = true;
      return it->second.data;
    }
    if (!loading_.count(key)) break;
    loaded_.wait(lock);  // another thread is reading it
  }
  if (damage_->isDamaged(*f, entry)) {  // found damaged before: not read again
    const ModelEntry& e = f->entries().at(size_t(entry));
    throw FormatError(f->path() + ": " + Partition::blockName(e.level, e.block) +
                      " is damaged (its checksum failed before)");
  }
  if (purpose == Purpose::Frame) stats_.misses++;
  if (wasHit) *wasHit = false;
  loading_.insert(key);
  // Room for the model before it is decoded (its floats: the stored form is smaller).
  const uint64_t reserve = f->entries()[size_t(entry)].size;
  const bool mayEvictPinned = purpose == Purpose::Frame && frameEvictsPinned_;
  if (!makeRoom(reserve, mayEvictPinned) && !mayEvictPinned) {  // not read: no room
    (purpose == Purpose::Frame ? stats_.frameDropped : stats_.prefetchDropped)++;
    loading_.erase(key);
    loaded_.notify_all();
    return nullptr;
  }
  reserved_ += reserve;
  lock.unlock();
  Payload data;
  try {
    data = load(*f, entry);
  } catch (...) {
    lock.lock();
    reserved_ -= reserve;
    loading_.erase(key);
    loaded_.notify_all();
    throw;
  }
  lock.lock();
  reserved_ -= reserve;
  loading_.erase(key);
  const uint64_t bytes = data->bytes();
  if (purpose == Purpose::Prefetch) {
    stats_.prefetchLoads++;
    stats_.prefetchBytes += bytes;
  }
  if (makeRoom(bytes, mayEvictPinned)) {
    lru_.push_front(key);
    map_[key] = Node{data, bytes, lru_.begin(), entry};
    resident_ += bytes;
    peakResident_ = std::max(peakResident_, resident_);
  } else if (purpose == Purpose::Frame) {
    stats_.bypasses++;
  } else {
    stats_.prefetchDropped++;
  }
  loaded_.notify_all();
  return data;
}

Payload LruCache::getIntact(int64_t entry, Purpose purpose) {
  return getIntactFrom(current(), entry, purpose);
}

Payload LruCache::getIntactFrom(const FilePtr& f, int64_t entry, Purpose purpose) {
  if (damage_->isDamaged(*f, entry)) return nullptr;
  try {
    return getFrom(f, entry, purpose, nullptr);
  } catch (const FormatError&) {
    if (damage_->isDamaged(*f, entry)) return nullptr;  // recorded by load(), here or elsewhere
    throw;
  }
}

bool LruCache::prefetch(int64_t entry) { return prefetch(current(), entry); }

bool LruCache::prefetch(const FilePtr& step, int64_t entry) {
  const uint64_t key = modelKey(step->entries().at(size_t(entry)));
  {
    std::lock_guard<std::mutex> g(mutex_);
    if (map_.count(key) || loading_.count(key)) return false;
  }
  if (damage_->isDamaged(*step, entry)) return false;
  return getIntactFrom(step, entry, Purpose::Prefetch) != nullptr;
}

Payload LruCache::takeLoaded(int64_t entry) {
  std::lock_guard<std::mutex> g(mutex_);
  auto it = map_.find(modelKey(file_->entries().at(size_t(entry))));
  if (it == map_.end()) return nullptr;
  lru_.splice(lru_.begin(), lru_, it->second.pos);
  return it->second.data;
}

Payload LruCache::residentHit(int64_t entry) {
  std::lock_guard<std::mutex> g(mutex_);
  auto it = map_.find(modelKey(file_->entries().at(size_t(entry))));
  if (it == map_.end()) return nullptr;
  stats_.hits++;
  lru_.splice(lru_.begin(), lru_, it->second.pos);
  return it->second.data;
}

bool LruCache::contains(int64_t entry) const {
  std::lock_guard<std::mutex> g(mutex_);  // the step's key and the lookup under one lock
  return map_.count(modelKey(file_->entries().at(size_t(entry)))) != 0;
}

bool LruCache::isDamaged(int64_t entry) const { return damage_->isDamaged(*current(), entry); }

void LruCache::setPinned(const std::vector<int64_t>& entries) {
  std::lock_guard<std::mutex> g(mutex_);
  pinned_.clear();
  for (const int64_t e : entries) pinned_.insert(modelKey(file_->entries().at(size_t(e))));
}

void LruCache::setKept(const std::vector<int64_t>& entries) {
  std::lock_guard<std::mutex> g(mutex_);
  kept_.clear();
  for (const int64_t e : entries) kept_.insert(modelKey(file_->entries().at(size_t(e))));
}

void LruCache::setFrameEvictsPinned(bool on) {
  std::lock_guard<std::mutex> g(mutex_);
  frameEvictsPinned_ = on;
}

void LruCache::setLoadHook(std::function<void(const AfamFile&, int64_t)> hook) {
  std::lock_guard<std::mutex> g(mutex_);
  loadHook_ = std::move(hook);
}

void LruCache::clearPinned() {
  std::lock_guard<std::mutex> g(mutex_);
  pinned_.clear();
}

CacheStats LruCache::stats() const {
  std::lock_guard<std::mutex> g(mutex_);
  return stats_;
}

void LruCache::resetStats() {
  std::lock_guard<std::mutex> g(mutex_);
  stats_ = CacheStats{};
}

uint64_t LruCache::takePeakResidentBytes() {
  std::lock_guard<std::mutex> g(mutex_);
  const uint64_t peak = std::max(peakResident_, resident_);
  peakResident_ = resident_;
  return peak;
}

uint64_t LruCache::residentBytes() const {
  std::lock_guard<std::mutex> g(mutex_);
  return resident_;
}

uint64_t LruCache::residentBlocks() const {
  std::lock_guard<std::mutex> g(mutex_);
  return map_.size();
}

std::vector<int64_t> LruCache::lruOrder() const {
  std::lock_guard<std::mutex> g(mutex_);
  std::vector<int64_t> out;
  for (const uint64_t key : lru_) out.push_back(map_.at(key).entry);
  return out;
}

}  // namespace afam
