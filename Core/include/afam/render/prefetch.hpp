// SPDX-License-Identifier: BSD-3-Clause
// Prefetching: a thread that loads the blocks the predicted next view (predict/predictor.hpp)
// will need into the RAM cache while the current frame renders (the paper's Algorithm 3).
//
// Protocol (the paper's rendering_done flag, with proper synchronisation): the frame thread calls
// start(job) just before it renders; the prefetch thread wakes on a condition variable and runs the
// job, which plans the predicted blocks and loads them one by one, checking an atomic stop flag
// between block loads. The frame thread calls finish() as soon as rendering is done: it sets the
// flag and waits (condition variable, no spinning) until the job has returned, which takes at most
// one block load. The thread then sleeps until the next start().
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "afam/render/cache.hpp"

namespace afam {

struct PrefetchStats {
  uint64_t jobs = 0, blocksLoaded = 0, stoppedEarly = 0;
};

class Prefetcher {
 public:
  /// A job gets the stop flag and must check it between block loads.
  using Job = std::function<void(const std::atomic<bool>& stop, uint64_t& loaded)>;

  /// nice: how much lower the thread's priority is than its maker's (thread_priority.hpp).
  explicit Prefetcher(int nice = 0);
  ~Prefetcher();  ///< stops and joins the thread
  Prefetcher(const Prefetcher&) = delete;
  Prefetcher& operator=(const Prefetcher&) = delete;

  /// Hands a job to the thread (a job still running is stopped first).
  void start(Job job);
  /// Sets the stop flag and blocks until the running job (if any) has returned.
  void finish();
  bool busy() const;
  PrefetchStats stats() const;

  /// Convenience job: loads `entries` in order through cache.prefetch until stopped.
  static Job loadJob(LruCache& cache, std::vector<int64_t> entries);

 private:
  void run(int nice);
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  Job job_;
  bool hasJob_ = false, running_ = false, quit_ = false;
  std::atomic<bool> stop_{false};
  PrefetchStats stats_;
  std::thread thread_;
};

}  // namespace afam
