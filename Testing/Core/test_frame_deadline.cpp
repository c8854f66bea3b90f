// SPDX-License-Identifier: BSD-3-Clause
// A frame keeps its deadline while the load threads decode on every core (issue 44): the load and
// prefetch threads run at a lower priority than the frame's thread, and the frame's wait for its
// loads ends early enough for its tail (what follows the wait) to fit the budget.
#include <gtest/gtest.h>

#include <algorithm>
#include <future>
#include <mutex>
#include <thread>

#include "afam/base/errors.hpp"
#include "afam/base/thread_priority.hpp"
#include "afam/render/block_loader.hpp"
#include "afam/render/prefetch.hpp"
#include "afam/render/renderer.hpp"
#include "afam/render/tail_reserve.hpp"
#include "render_test_util.hpp"

using namespace afam;
using Clock = std::chrono::steady_clock;

namespace {

std::shared_ptr<const AfamFile> smallFile() {
  return afam_test::encodeMl(33, EncodingMode::Fixed, 3, 4, 1e-3, 5);
}

/// The nice value of a thread that lowers itself by `step` (the test's own thread stays as it is).
int niceAfter(int step) {
  int nice = 0;
  std::thread([&] {
    lowerThisThreadPriority(step);
    nice = thisThreadNice();
  }).join();
  return nice;
}

}  // namespace

TEST(ThreadPriority, AThreadLowersItselfAndNoFurtherThan19) {
#if !defined(__linux__)
  GTEST_SKIP() << "threads have a nice value of their own on Linux only";
#endif
  const int base = thisThreadNice();
  EXPECT_EQ(niceAfter(0), base);
  EXPECT_EQ(niceAfter(3), std::min(19, base + 3));
  EXPECT_EQ(niceAfter(40), 19);
  EXPECT_EQ(thisThreadNice(), base) << "the caller's thread is left as it was";
}

TEST(ThreadPriority, LoadAndPrefetchThreadsRunBelowTheFrame) {
#if !defined(__linux__)
  GTEST_SKIP() << "threads have a nice value of their own on Linux only";
#endif
  const int base = thisThreadNice();
  auto file = smallFile();
  LruCache cache(file, CacheBudget{});
  std::mutex m;
  std::vector<int> seen;
  cache.setLoadHook([&](const AfamFile&, int64_t) {
    std::lock_guard<std::mutex> g(m);
    seen.push_back(thisThreadNice());
  });
  {
    BlockLoader loader(cache, 2, 5);
    loader.request({0, 1, 2, 3}, LruCache::Purpose::Frame);
    ASSERT_TRUE(loader.waitIdle(Clock::now() + std::chrono::seconds(60)));
  }
  ASSERT_EQ(seen.size(), 4u);
  for (const int n : seen) EXPECT_EQ(n, std::min(19, base + 5));
  std::promise<int> prefetchNice;
  {
    Prefetcher p(7);
    p.start([&](const std::atomic<bool>&, uint64_t&) { prefetchNice.set_value(thisThreadNice()); });
    EXPECT_EQ(prefetchNice.get_future().get(), std::min(19, base + 7));
    p.finish();
  }
  EXPECT_EQ(thisThreadNice(), base);
}

TEST(ThreadPriority, ARendererRefusesANiceStepOutside0To19) {
  RenderOptions o;
  o.loadNice = 20;
  EXPECT_THROW(Renderer(smallFile(), o), InvalidArgument);
  o.loadNice = -1;
  EXPECT_THROW(Renderer(smallFile(), o), InvalidArgument);
}

TEST(TailReserve, TheWaitEndsTheLargestRecentTailBeforeTheBudget) {
  TailReserve r;
  EXPECT_DOUBLE_EQ(r.waitMs(20), 20) << "no tail seen yet";
  r.observe(4);
  EXPECT_DOUBLE_EQ(r.waitMs(20), 16);
  r.observe(2);  // a shorter tail: the larger one decays
  EXPECT_DOUBLE_EQ(r.reserveMs(), 4 * TailReserve::kDecay);
  r.observe(6);
  EXPECT_DOUBLE_EQ(r.waitMs(20), 14);
  r.observe(50);  // never more than half the budget
  EXPECT_DOUBLE_EQ(r.waitMs(20), 10);
  EXPECT_DOUBLE_EQ(r.waitMs(0), 0) << "a budget of 0 does not wait";
  EXPECT_DOUBLE_EQ(r.waitMs(1e12), TailReserve::kMaxBudgetMs - 50);
  r.observe(-3);  // a clock that went backwards counts as no tail
  EXPECT_DOUBLE_EQ(r.reserveMs(), 50 * TailReserve::kDecay);
}
