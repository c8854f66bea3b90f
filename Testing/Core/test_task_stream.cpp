// SPDX-License-Identifier: BSD-3-Clause
// The encoder's worker pool (threads kept between runs) and the task stream over it.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <map>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "afam/base/task_stream.hpp"
#include "afam/base/worker_pool.hpp"

using namespace afam;

namespace {
const auto kNoTick = [] { return true; };
}  // namespace

TEST(WorkerPool, EachWorkerIsOneThreadAcrossRunsAndEveryTaskRunsOnce) {
  WorkerPool pool(4);
  std::mutex m;
  std::map<int, std::set<std::thread::id>> threadsOf;  // worker -> the threads it ran on
  std::set<std::thread::id> all;
  for (int run = 0; run < 5; ++run) {
    std::vector<std::atomic<int>> ran(37);
    pool.run(
        37,
        [&](int w, int64_t t) {
          ran[size_t(t)]++;
          std::lock_guard<std::mutex> lock(m);
          threadsOf[w].insert(std::this_thread::get_id());
          all.insert(std::this_thread::get_id());
        },
        kNoTick);
    for (const auto& r : ran) EXPECT_EQ(r.load(), 1);
  }
  for (const auto& [w, ids] : threadsOf) {
    EXPECT_GE(w, 0);
    EXPECT_LT(w, 4);
    EXPECT_EQ(ids.size(), 1u) << "worker " << w << " ran on " << ids.size() << " threads";
  }
  EXPECT_LE(all.size(), 4u);
  EXPECT_EQ(all.count(std::this_thread::get_id()), 0u);  // the caller waits and ticks
}

TEST(WorkerPool, AfterATaskThrowsTheFirstErrorIsRethrownAndThePoolRunsAgain) {
  WorkerPool pool(3);
  EXPECT_THROW(pool.run(
                   50,
                   [](int, int64_t t) {
                     if (t == 7) throw std::runtime_error("task 7");
                   },
                   kNoTick),
               std::runtime_error);
  std::atomic<int64_t> sum{0};
  pool.run(
      100, [&](int, int64_t t) { sum += t; }, kNoTick);
  EXPECT_EQ(sum.load(), 4950);
  // Fewer tasks than workers: only as many workers take part.
  std::atomic<int> maxWorker{-1};
  pool.run(
      2, [&](int w, int64_t) { maxWorker = std::max(maxWorker.load(), w); }, kNoTick);
  EXPECT_LE(maxWorker.load(), 1);
}

TEST(TaskStream, TasksPublishedInBatchesAreHandedOnInOrderAsTheyAreDone) {
  WorkerPool pool(4);
  constexpr int64_t kCount = 60;
  std::atomic<int> working{0}, mostAtOnce{0};
  TaskStream<int64_t> stream(pool, kCount, [&](int, int64_t& v) {
    const int now = ++working;
    int seen = mostAtOnce.load();
    while (now > seen && !mostAtOnce.compare_exchange_weak(seen, now)) {
    }
    // Later tasks finish first within a batch: the order handed on is still the publishing order.
    std::this_thread::sleep_for(std::chrono::microseconds(200 * (10 - v % 10)));
    v = v * v;
    --working;
  });
  std::vector<int64_t> handed;
  const auto take = [&](int64_t& v) { handed.push_back(v); };
  int ticks = 0;
  const auto tick = [&] { return ++ticks > 0; };
  for (int64_t b = 0; b < kCount; b += 10) {
    std::vector<int64_t> batch;
    for (int64_t i = b; i < b + 10; ++i) batch.push_back(i);
    stream.publish(std::move(batch));
    EXPECT_EQ(stream.published(), b + 10);
    ASSERT_TRUE(stream.drain(b, take, tick));  // everything before this batch is done
    EXPECT_GE(int64_t(handed.size()), b);
  }
  ASSERT_TRUE(stream.drain(kCount, take, tick));
  ASSERT_EQ(int64_t(handed.size()), kCount);
  for (int64_t i = 0; i < kCount; ++i) EXPECT_EQ(handed[size_t(i)], i * i);
  EXPECT_GT(mostAtOnce.load(), 1);           // the pool's threads worked side by side
  EXPECT_THROW(stream.publish({1}), Error);  // more than the stream holds
}

TEST(TaskStream, ThreadsWaitForTasksNotYetPublishedAndTheWaitIsCounted) {
  WorkerPool pool(2);
  TaskStream<int> stream(pool, 4, [](int, int& v) { v += 1; });
  std::this_thread::sleep_for(std::chrono::milliseconds(150));  // both threads wait for tasks
  stream.publish({10, 20});
  std::vector<int> got;
  ASSERT_TRUE(stream.drain(
      2, [&](int& v) { got.push_back(v); }, kNoTick));
  EXPECT_EQ(got, (std::vector<int>{11, 21}));
  // Two threads waited about 150 ms each, less their start-up (slow under a sanitizer).
  EXPECT_GE(stream.waitSeconds(), 0.1);
  EXPECT_THROW(stream.drain(
                   3, [](int&) {}, kNoTick),
               Error);  // task 2 is not published
  stream.publish({30, 40});
  ASSERT_TRUE(stream.drain(
      4, [&](int& v) { got.push_back(v); }, kNoTick));
  EXPECT_EQ(got, (std::vector<int>{11, 21, 31, 41}));
}

TEST(TaskStream, ATaskErrorReachesTheDrainAndTheStreamStopsCleanly) {
  WorkerPool pool(3);
  {
    TaskStream<int> stream(pool, 100, [](int, int& v) {
      if (v == 13) throw std::runtime_error("task 13 failed");
    });
    std::vector<int> tasks;
    for (int i = 0; i < 50; ++i) tasks.push_back(i);
    stream.publish(std::move(tasks));  // the other 50 never come: waiting threads must leave
    int handed = 0;
    try {
      stream.drain(
          50, [&](int&) { ++handed; }, kNoTick);
      ADD_FAILURE() << "the task's error was not rethrown";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "task 13 failed");
    }
    EXPECT_LE(handed, 13);  // never past the failed task
  }
  // A stream left early (the caller's own error, tasks never published) stops without hanging,
  // and the pool serves the next stream.
  {
    TaskStream<int> idle(pool, 10, [](int, int&) {});
  }
  TaskStream<int> next(pool, 3, [](int, int& v) { v *= 2; });
  next.publish({1, 2, 3});
  int sum = 0;
  ASSERT_TRUE(next.drain(
      3, [&](int& v) { sum += v; }, kNoTick));
  EXPECT_EQ(sum, 12);
}

TEST(TaskStream, ATickThatSaysStopEndsTheDrain) {
  WorkerPool pool(2);
  std::atomic<bool> release{false};
  TaskStream<int> stream(pool, 2, [&](int, int&) {
    while (!release.load()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  });
  stream.publish({1, 2});
  int ticks = 0;
  EXPECT_FALSE(stream.drain(
      2, [](int&) {}, [&] { return ++ticks < 3; }));
  EXPECT_EQ(ticks, 3);
  release = true;  // the tasks under way finish; the destructor waits for them
}
