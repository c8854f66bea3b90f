// SPDX-License-Identifier: BSD-3-Clause
// Tasks streamed through a worker pool and handed on in order (private to Core).
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/base/worker_pool.hpp"

namespace afam {

/// A known number of tasks streamed through a pool: the calling thread publishes them in order, a
/// batch at a time (as they are made: the encoder's blocks as they are sampled), the pool's
/// threads work on each once it is published (a thread done with a batch's tasks goes on to the
/// next batch's, none waits at a batch's end for another's last task), and the calling thread
/// hands the done tasks on in order (drain). The pool runs on a thread of its own from
/// construction until every task is done or the stream stops; the destructor stops it and waits.
template <typename Task>
class TaskStream {
 public:
  using Work = std::function<void(int worker, Task& task)>;
  TaskStream(WorkerPool& pool, int64_t count, Work work)
      : count_(count),
        work_(std::move(work)),
        tasks_(size_t(count)),
        done_(new std::atomic<uint8_t>[size_t(count)]) {
    for (int64_t t = 0; t < count; ++t) done_[size_t(t)] = 0;
    running_ = std::async(std::launch::async, [this, &pool] {
      struct Ended {  // tells drain, however the run leaves
        TaskStream& s;
        ~Ended() {
          std::lock_guard<std::mutex> lock(s.m_);
          s.ended_ = true;
          s.doneCv_.notify_all();
        }
      } ended{*this};
      pool.run(
          count_, [this](int w, int64_t t) { workOn(w, t); }, [this] { return !stopped_.load(); });
    });
  }
  ~TaskStream() { stop(); }
  TaskStream(const TaskStream&) = delete;
  TaskStream& operator=(const TaskStream&) = delete;

  /// Appends the next tasks (at most count() in all) and wakes the threads waiting for them.
  void publish(std::vector<Task>&& tasks) {
    const int64_t first = published_.load();
    if (first + int64_t(tasks.size()) > count_)
      throw Error("TaskStream: more tasks published than the stream holds");
    for (size_t i = 0; i < tasks.size(); ++i) tasks_[size_t(first) + i] = std::move(tasks[i]);
    {
      std::lock_guard<std::mutex> lock(m_);
      published_.store(first + int64_t(tasks.size()));
    }
    publishedCv_.notify_all();
  }

  /// Hands the done tasks on, in order, to `take` until the first `upTo` have been (waiting for
  /// them, published ones only). Calls `tick` after handing tasks on (at most every 10 ms, and
  /// always after the last of a drain) and about every 100 ms while it waits; false when tick
  /// returned false. Rethrows what a task threw.
  bool drain(int64_t upTo, const std::function<void(Task&)>& take,
             const std::function<bool()>& tick) {
    if (upTo > published_.load())
      throw Error("TaskStream: drain to task " + std::to_string(upTo) + " of " +
                  std::to_string(published_.load()) + " published");
    for (;;) {
      const bool ended = ended_.load();  // read first: an ended run's tasks are then all seen
      const int64_t before = handedOn_;
      while (handedOn_ < published_.load() && done_[size_t(handedOn_)].load() != 0) {
        take(tasks_[size_t(handedOn_)]);
        tasks_[size_t(handedOn_)] = Task{};  // what it held is handed on
        ++handedOn_;
      }
      const auto now = std::chrono::steady_clock::now();
      if (handedOn_ > before &&
          (handedOn_ >= upTo || now - lastTick_ >= std::chrono::milliseconds(10))) {
        lastTick_ = now;
        if (!tick()) return false;
      }
      if (handedOn_ >= upTo) return true;
      if (ended) {
        if (failure_) std::rethrow_exception(failure_);  // set before the run ended
        running_.get();
        throw Error("TaskStream: the run ended before task " + std::to_string(handedOn_));
      }
      std::unique_lock<std::mutex> lock(m_);
      if (!doneCv_.wait_for(lock, std::chrono::milliseconds(100), [&] {
            return ended_.load() || done_[size_t(handedOn_)].load() != 0;
          })) {
        lock.unlock();
        lastTick_ = std::chrono::steady_clock::now();
        if (!tick()) return false;
      }
    }
  }

  int64_t count() const { return count_; }
  int64_t published() const { return published_.load(); }
  /// Seconds the pool's threads together waited for tasks to be published.
  double waitSeconds() const { return 1e-9 * double(waitNanos_.load()); }

 private:
  /// Thrown by a thread waiting for a task when the stream stops (ends the pool's run).
  struct Stopped {};

  void workOn(int worker, int64_t t) {
    if (published_.load() <= t) {
      const auto t0 = std::chrono::steady_clock::now();
      std::unique_lock<std::mutex> lock(m_);
      publishedCv_.wait(lock, [&] { return published_.load() > t || stopped_.load(); });
      waitNanos_ += std::chrono::duration_cast<std::chrono::nanoseconds>(
                        std::chrono::steady_clock::now() - t0)
                        .count();
      if (published_.load() <= t) throw Stopped{};
    }
    try {
      work_(worker, tasks_[size_t(t)]);
    } catch (...) {  // the first error ends the stream: threads waiting for tasks leave
      std::lock_guard<std::mutex> lock(m_);
      if (!failure_) failure_ = std::current_exception();
      stopped_ = true;
      publishedCv_.notify_all();
      throw;
    }
    done_[size_t(t)].store(1);
    std::lock_guard<std::mutex> lock(m_);
    doneCv_.notify_all();
  }

  /// No more tasks: threads waiting for one leave and the run ends; waits for it.
  void stop() {
    {
      std::lock_guard<std::mutex> lock(m_);
      stopped_ = true;
    }
    publishedCv_.notify_all();
    if (!running_.valid()) return;
    try {
      running_.get();
    } catch (...) {  // drain rethrew a task's error, or the caller leaves with its own
    }
  }

  const int64_t count_;
  Work work_;
  std::vector<Task> tasks_;
  std::unique_ptr<std::atomic<uint8_t>[]> done_;
  std::atomic<int64_t> published_{0};
  int64_t handedOn_ = 0;  ///< the calling thread's alone, as is lastTick_
  std::chrono::steady_clock::time_point lastTick_{};
  std::atomic<bool> stopped_{false}, ended_{false};
  std::atomic<int64_t> waitNanos_{0};
  std::exception_ptr failure_;  ///< the first error a task threw (guarded by m_)
  std::mutex m_;
  std::condition_variable publishedCv_, doneCv_;
  std::future<void> running_;  ///< the pool's run (stop waits for it)
};

}  // namespace afam
