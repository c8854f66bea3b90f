// SPDX-License-Identifier: BSD-3-Clause
// A fixed-size pool of worker threads for the encoder (private to Core).
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace afam {

// Fixed-size worker pool: run(count, fn) calls fn(worker, task) for task in [0, count) on all
// workers; the calling thread waits and calls `tick` about every 100 ms (tick returning false
// stops the handing-out of tasks). The first exception thrown by a task is rethrown by run().
//
// The threads are started by the first run and kept until the pool is destroyed: worker w is the
// same thread in every run, so what a thread keeps of its own (thread-local scratch, its zstd
// context, its file staging) is made once per pool, not once per run. One run at a time: run()
// from several threads at once takes turns; run() from inside a task of the same pool deadlocks.
class WorkerPool {
 public:
  explicit WorkerPool(int workers) : workers_(std::max(1, workers)) {}
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;
  ~WorkerPool() {
    {
      std::lock_guard<std::mutex> lock(m_);
      quit_ = true;
    }
    wake_.notify_all();
    for (std::thread& t : threads_) t.join();
  }

  template <typename Fn, typename Tick>
  void run(int64_t count, Fn&& fn, Tick&& tick) {
    std::lock_guard<std::mutex> turn(runMutex_);
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
    const int nThreads = int(std::min<int64_t>(workers_, std::max<int64_t>(count, 1)));
    const std::function<void(int)> job = body;
    start(nThreads, job);
    {
      std::unique_lock<std::mutex> lock(m);
      while (done.load() < count && !stop.load()) {
        cv.wait_for(lock, std::chrono::milliseconds(100));
        lock.unlock();
        if (!tick()) stop = true;
        lock.lock();
      }
    }
    finish();
    if (error) std::rethrow_exception(error);
  }
  int workers() const { return workers_; }

 private:
  /// Hands `job` (which outlives the job: finish) to workers [0, n), starting the threads not
  /// yet running.
  void start(int n, const std::function<void(int)>& job) {
    std::lock_guard<std::mutex> lock(m_);
    while (int(threads_.size()) < workers_)
      threads_.emplace_back([this, w = int(threads_.size())] { serve(w); });
    job_ = &job;
    jobWorkers_ = n;
    busy_ = n;
    ++generation_;
    wake_.notify_all();
  }
  /// Waits until every worker given the job has left it.
  void finish() {
    std::unique_lock<std::mutex> lock(m_);
    idle_.wait(lock, [this] { return busy_ == 0; });
    job_ = nullptr;
  }
  void serve(int w) {
    uint64_t seen = 0;
    std::unique_lock<std::mutex> lock(m_);
    for (;;) {
      wake_.wait(lock, [&] { return quit_ || generation_ != seen; });
      if (quit_) return;
      seen = generation_;
      if (w >= jobWorkers_) continue;
      const std::function<void(int)>* job = job_;
      lock.unlock();
      (*job)(w);
      lock.lock();
      if (--busy_ == 0) idle_.notify_all();
    }
  }

  int workers_;
  std::mutex runMutex_;  ///< one run at a time
  std::mutex m_;         ///< guards what follows
  std::condition_variable wake_, idle_;
  std::vector<std::thread> threads_;
  const std::function<void(int)>* job_ = nullptr;
  int jobWorkers_ = 0, busy_ = 0;
  uint64_t generation_ = 0;
  bool quit_ = false;
};

}  // namespace afam
