// SPDX-License-Identifier: BSD-3-Clause
#include "afam/render/block_loader.hpp"

#include <algorithm>

#include "afam/base/errors.hpp"
#include "afam/base/thread_priority.hpp"
#include "afam/base/thread_scratch.hpp"

namespace afam {

BlockLoader::BlockLoader(LruCache& cache, int threads, int nice) : cache_(cache) {
  if (threads < 1) threads = int(std::max(1u, std::thread::hardware_concurrency()));
  workers_.reserve(size_t(threads));
  for (int t = 0; t < threads; ++t) workers_.emplace_back([this, nice] { run(nice); });
}

BlockLoader::~BlockLoader() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    quit_ = true;
    frameQueue_.clear();
    prefetchQueue_.clear();
    stepQueue_.clear();
  }
  work_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void BlockLoader::enqueue(const std::vector<int64_t>& entries, bool frame) {
  for (const int64_t e : entries) {
    if (loading_.count(e) || cache_.contains(e)) continue;
    if (queued_.count(e)) {
      if (!frame) continue;
      auto it = std::find(prefetchQueue_.begin(), prefetchQueue_.end(), e);
      if (it == prefetchQueue_.end()) continue;  // already a frame request
      prefetchQueue_.erase(it);
    } else {
      queued_.insert(e);
    }
    (frame ? frameQueue_ : prefetchQueue_).push_back(e);
  }
}

void BlockLoader::request(const std::vector<int64_t>& entries, LruCache::Purpose purpose) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    enqueue(entries, purpose == LruCache::Purpose::Frame);
  }
  work_.notify_all();
}

void BlockLoader::requestFrame(const std::vector<int64_t>& entries) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const int64_t e : frameQueue_) queued_.erase(e);
    frameQueue_.clear();
    enqueue(entries, true);
  }
  work_.notify_all();
  done_.notify_all();  // waiters on a dropped request
}

size_t BlockLoader::pendingOf(const std::vector<int64_t>& entries) const {
  size_t n = 0;
  for (const int64_t e : entries) n += (queued_.count(e) || loading_.count(e)) ? 1 : 0;
  return n;
}

size_t BlockLoader::waitFor(const std::vector<int64_t>& entries, Clock::time_point deadline) {
  std::unique_lock<std::mutex> lock(mutex_);
  size_t left = pendingOf(entries);
  while (left > 0 && done_.wait_until(lock, deadline) != std::cv_status::timeout)
    left = pendingOf(entries);
  return pendingOf(entries);
}

bool BlockLoader::waitIdle(Clock::time_point deadline) {
  std::unique_lock<std::mutex> lock(mutex_);
  return done_.wait_until(lock, deadline, [this] {
    return frameQueue_.empty() && prefetchQueue_.empty() && stepQueue_.empty() &&
           loading_.empty() && !stepLoading_;
  });
}

bool BlockLoader::pending(int64_t entry) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return queued_.count(entry) || loading_.count(entry);
}

void BlockLoader::cancelPrefetch() {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const int64_t e : prefetchQueue_) queued_.erase(e);
  prefetchQueue_.clear();
  done_.notify_all();
}

void BlockLoader::requestStep(std::shared_ptr<const AfamFile> step,
                              const std::vector<int64_t>& entries) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    step_ = std::move(step);
    stepQueue_.assign(entries.begin(), entries.end());
  }
  work_.notify_all();
}

std::vector<std::string> BlockLoader::takeErrors() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<std::string> out;
  out.swap(errors_);
  return out;
}

BlockLoaderStats BlockLoader::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

void BlockLoader::loadOtherStep(std::unique_lock<std::mutex>& lock) {
  const int64_t entry = stepQueue_.front();
  stepQueue_.pop_front();
  const std::shared_ptr<const AfamFile> step = step_;
  ++stepLoading_;
  lock.unlock();
  try {
    cache_.prefetch(step, entry);
  } catch (const std::exception&) {
    // the step's frame reads it again and reports what is wrong
  }
  lock.lock();
  --stepLoading_;
  stats_.stepLoads++;
  done_.notify_all();
}

void BlockLoader::run(int nice) {
  lowerThisThreadPriority(nice);  // where it cannot, loads run at the frame's priority
  std::unique_lock<std::mutex> lock(mutex_);
  const auto hasWork = [this] {
    return quit_ || !frameQueue_.empty() || !prefetchQueue_.empty() || !stepQueue_.empty();
  };
  for (;;) {
    if (!hasWork()) {  // idle: the decoding scratch goes back until the next burst of loads
      lock.unlock();
      releaseThreadScratch();
      lock.lock();
    }
    work_.wait(lock, hasWork);
    if (quit_) return;
    if (frameQueue_.empty() && prefetchQueue_.empty()) {
      loadOtherStep(lock);
      continue;
    }
    const bool frame = !frameQueue_.empty();
    std::deque<int64_t>& queue = frame ? frameQueue_ : prefetchQueue_;
    const int64_t entry = queue.front();
    queue.pop_front();
    queued_.erase(entry);
    loading_.insert(entry);
    lock.unlock();
    std::string error;
    try {
      if (frame)
        cache_.getIntact(entry, LruCache::Purpose::Frame);
      else
        cache_.prefetch(entry);
    } catch (const std::exception& e) {
      error = e.what();
    }
    lock.lock();
    loading_.erase(entry);
    (frame ? stats_.frameLoads : stats_.prefetchLoads)++;
    if (!error.empty()) {
      stats_.failed++;
      errors_.push_back(std::move(error));
    }
    done_.notify_all();
  }
}

}  // namespace afam
