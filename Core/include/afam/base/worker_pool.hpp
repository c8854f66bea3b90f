// SPDX-License-Identifier: BSD-3-Clause
// A fixed-size pool of worker threads for the encoder (private to Core).
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace afam {

// Fixed-size worker pool: run(count, fn) calls fn(worker, task) for task in [0, count) on all
// workers; the calling thread waits and calls `tick` about every 100 ms (tick returning false
// stops the handing-out of tasks). The first exception thrown by a task is rethrown by run().
class WorkerPool {
 public:
  explicit WorkerPool(int workers) : workers_(std::max(1, workers)) {}
  template <typename Fn, typename Tick>
  void run(int64_t count, Fn&& fn, Tick&& tick) {
    std::atomic<int64_t> next{0}, done{0};
    std::atomic<bool> stop{false};
    std::exception_ptr error;
    std::mutex m;
    std::condition_variable cv;
    auto body = [&](int w) {
      for (;;) {
        if (stop.load()) break;
        const int64_t t = next.fetch_add(1);
        if (t >= count) break;
        try {
          fn(w, t);
        } catch (...) {
          std::lock_guard<std::mutex> lock(m);
          if (!error) error = std::current_exception();
          stop = true;
        }
        if (done.fetch_add(1) + 1 == count) {
          std::lock_guard<std::mutex> lock(m);
          cv.notify_all();
        }
      }
      std::lock_guard<std::mutex> lock(m);
      cv.notify_all();
    };
    std::vector<std::thread> threads;
    const int nThreads = int(std::min<int64_t>(workers_, std::max<int64_t>(count, 1)));
    threads.reserve(size_t(nThreads));
    for (int w = 0; w < nThreads; ++w) threads.emplace_back(body, w);
    {
      std::unique_lock<std::mutex> lock(m);
      while (done.load() < count && !stop.load()) {
        cv.wait_for(lock, std::chrono::milliseconds(100));
        lock.unlock();
        if (!tick()) stop = true;
        lock.lock();
      }
    }
    for (auto& t : threads) t.join();
    if (error) std::rethrow_exception(error);
  }
  int workers() const { return workers_; }

 private:
  int workers_;
};

}  // namespace afam
