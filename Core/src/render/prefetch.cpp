// SPDX-License-Identifier: BSD-3-Clause
#include "afam/render/prefetch.hpp"

#include "afam/base/errors.hpp"
#include "afam/base/thread_priority.hpp"
#include "afam/base/thread_scratch.hpp"

namespace afam {

Prefetcher::Prefetcher(int nice) : thread_([this, nice] { run(nice); }) {}

Prefetcher::~Prefetcher() {
  {
    std::lock_guard<std::mutex> g(mutex_);
    quit_ = true;
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

void Prefetcher::start(Job job) {
  finish();
  {
    std::lock_guard<std::mutex> g(mutex_);
    job_ = std::move(job);
    hasJob_ = true;
    stop_ = false;
  }
  cv_.notify_all();
}

void Prefetcher::finish() {
  std::unique_lock<std::mutex> lock(mutex_);
  stop_ = true;
  if (hasJob_ && !running_) {  // not picked up yet: drop it
    hasJob_ = false;
    job_ = nullptr;
  }
  cv_.wait(lock, [this] { return !running_; });
}

bool Prefetcher::busy() const {
  std::lock_guard<std::mutex> g(mutex_);
  return running_ || hasJob_;
}

PrefetchStats Prefetcher::stats() const {
  std::lock_guard<std::mutex> g(mutex_);
  return stats_;
}

void Prefetcher::run(int nice) {
  lowerThisThreadPriority(nice);
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    cv_.wait(lock, [this] { return quit_ || hasJob_; });
    if (quit_) return;
    Job job = std::move(job_);
    job_ = nullptr;
    hasJob_ = false;
    running_ = true;
    lock.unlock();
    uint64_t loaded = 0;
    try {
      if (job) job(stop_, loaded);
      releaseThreadScratch();  // until the next job
    } catch (...) {
      releaseThreadScratch();
      // A failed prefetch read is not fatal. A damaged payload never gets here (the cache records
      // it and skips it); another error (I/O) is met again by the frame that needs the block,
      // which reports it.
    }
    lock.lock();
    running_ = false;
    stats_.jobs++;
    stats_.blocksLoaded += loaded;
    if (stop_) stats_.stoppedEarly++;
    cv_.notify_all();
  }
}

Prefetcher::Job Prefetcher::loadJob(LruCache& cache, std::vector<int64_t> entries) {
  return [&cache, entries = std::move(entries)](const std::atomic<bool>& stop, uint64_t& loaded) {
    for (int64_t e : entries) {
      if (stop.load(std::memory_order_acquire)) return;
      if (cache.prefetch(e)) ++loaded;
    }
  };
}

}  // namespace afam
