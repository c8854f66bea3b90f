// SPDX-License-Identifier: BSD-3-Clause
// Loads micro-models into the RAM cache on a pool of threads, so that a frame's misses are read
// and decoded by every core at once rather than one after another on the frame's critical path,
// and a load the frame does not wait for goes on after the frame (the next frames find it
// resident: progressive refinement).
//
// Frame requests are served before prefetch requests, each in the order given (most important
// first); an entry already queued or loading is not queued twice, and a frame request for an
// entry queued for prefetching moves it up. A load goes through LruCache (getIntact for frames:
// a damaged payload is recorded in the cache's DamageLog, not thrown; prefetch for prefetching,
// which never evicts pinned blocks). Any other error of a load (I/O, a file changed on disk) is
// kept and handed out once by takeErrors(); its entry counts as done, not resident.
//
// The load threads run `nice` steps below the thread that made the loader (thread_priority.hpp):
// a frame's thread waking at its deadline takes a core from them at once.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <unordered_set>
#include <vector>

#include "afam/render/cache.hpp"

namespace afam {

struct BlockLoaderStats {
  uint64_t frameLoads = 0, prefetchLoads = 0, failed = 0;
  uint64_t stepLoads = 0;  ///< requestStep's, tried
};

class BlockLoader {
 public:
  using Clock = std::chrono::steady_clock;
  /// threads < 1: one per core; nice: how much lower their priority is (0: the same). The cache
  /// must outlive the loader.
  BlockLoader(LruCache& cache, int threads, int nice = 0);
  ~BlockLoader();  ///< drops what is queued, waits for the loads under way
  BlockLoader(const BlockLoader&) = delete;
  BlockLoader& operator=(const BlockLoader&) = delete;

  /// Queues the entries not already resident, queued or loading.
  void request(const std::vector<int64_t>& entries, LruCache::Purpose purpose);
  /// A new frame's misses, most important first: frame requests of earlier frames not started
  /// yet are dropped (a view that moved on no longer needs them; the frames that still do ask
  /// again), then `entries` are queued as request() does.
  void requestFrame(const std::vector<int64_t>& entries);
  /// Waits until none of `entries` is queued or loading, or until `deadline`. Returns how many
  /// still are.
  size_t waitFor(const std::vector<int64_t>& entries, Clock::time_point deadline);
  /// Waits until nothing is queued or loading (every queue, requestStep's included), or until
  /// `deadline`; true when idle.
  bool waitIdle(Clock::time_point deadline);
  /// True while the entry is queued or being loaded.
  bool pending(int64_t entry) const;
  /// Drops the prefetch requests not started yet (not those of requestStep).
  void cancelPrefetch();
  /// Queues `entries` of another step of the run (the next one, while this one is shown), served
  /// after every frame and prefetch request, replacing what an earlier call queued and was not
  /// started; they stay queued when a frame ends (LruCache::prefetch(step, entry) loads them).
  void requestStep(std::shared_ptr<const AfamFile> step, const std::vector<int64_t>& entries);
  /// Messages of loads that failed (other than damage), each handed out once.
  std::vector<std::string> takeErrors();
  BlockLoaderStats stats() const;
  int threads() const { return int(workers_.size()); }

 private:
  void run(int nice);
  void enqueue(const std::vector<int64_t>& entries, bool frame);  // under the lock
  void loadOtherStep(std::unique_lock<std::mutex>& lock);         // one of stepQueue_, lock held
  size_t pendingOf(const std::vector<int64_t>& entries) const;    // under the lock

  LruCache& cache_;
  mutable std::mutex mutex_;
  std::condition_variable work_, done_;
  std::deque<int64_t> frameQueue_, prefetchQueue_, stepQueue_;
  std::shared_ptr<const AfamFile> step_;  ///< the file stepQueue_'s entries are of
  int stepLoading_ = 0;                   ///< requestStep loads under way
  std::unordered_set<int64_t> queued_, loading_;
  std::vector<std::string> errors_;
  BlockLoaderStats stats_;
  bool quit_ = false;
  std::vector<std::thread> workers_;
};

}  // namespace afam
