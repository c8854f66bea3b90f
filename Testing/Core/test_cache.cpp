// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <random>
#include <thread>

#include "afam/base/errors.hpp"
#include "afam/base/thread_scratch.hpp"
#include "afam/predict/predictor_factory.hpp"
#include "afam/render/cache.hpp"
#include "afam/render/prefetch.hpp"
#include "render_test_util.hpp"

using namespace afam;

namespace {
std::shared_ptr<const AfamFile> smallFile() {
  return afam_test::encodeMl(33, EncodingMode::Fixed, 3, 4, 1e-3, 5);  // 5^3 floats = 500 B each
}
}  // namespace

TEST(Cache, EvictsLeastRecentlyUsedFirst) {
  auto file = smallFile();
  LruCache cache(file, CacheBudget{0, 3});
  bool hit = true;
  cache.get(0, LruCache::Purpose::Frame, &hit);
  EXPECT_FALSE(hit);
  cache.get(1);
  cache.get(2);
  EXPECT_EQ(cache.lruOrder(), (std::vector<int64_t>{2, 1, 0}));
  cache.get(0, LruCache::Purpose::Frame, &hit);  // touch 0: 1 becomes least recent
  EXPECT_TRUE(hit);
  cache.get(3);
  EXPECT_EQ(cache.lruOrder(), (std::vector<int64_t>{3, 0, 2}));
  EXPECT_FALSE(cache.contains(1));
  const CacheStats s = cache.stats();
  EXPECT_EQ(s.hits, 1u);
  EXPECT_EQ(s.misses, 4u);
  EXPECT_EQ(s.evictions, 1u);
  EXPECT_EQ(s.bytesRead, 4 * file->entries()[0].size);
}

TEST(Cache, BudgetsAreNeverExceeded) {
  auto file = smallFile();
  const int64_t n = int64_t(file->entries().size());
  std::mt19937 rng(1);
  for (CacheBudget b : {CacheBudget{2000, 0}, CacheBudget{0, 7}, CacheBudget{3333, 5}}) {
    LruCache cache(file, b);
    std::uniform_int_distribution<int64_t> pick(0, n - 1);
    for (int i = 0; i < 400; ++i) {
      if (i % 3 == 0)
        cache.prefetch(pick(rng));
      else
        cache.get(pick(rng));
      if (b.bytes) {
        ASSERT_LE(cache.residentBytes(), b.bytes);
      }
      if (b.blocks) {
        ASSERT_LE(cache.residentBlocks(), b.blocks);
      }
    }
  }
}

TEST(Cache, TheByteBudgetCountsDecodingScratch) {
  auto file = smallFile();  // uncoded models: loading them takes no scratch
  ASSERT_EQ(file->entries()[0].storedSize, 500u);
  releaseAllThreadScratch();  // what tests before this one left on this thread
  ASSERT_EQ(threadScratchBytes(), 0u);
  LruCache cache(file, CacheBudget{2000, 0});
  std::mutex m;
  std::condition_variable cv;
  bool holding = false, done = false;
  std::thread decoder([&] {  // a thread holding 1408 B of decoding scratch until told
    threadScratch<uint8_t>(ScratchSlot::Words, 1400);
    std::unique_lock<std::mutex> lock(m);
    holding = true;
    cv.notify_all();
    cv.wait(lock, [&] { return done; });
  });
  {
    std::unique_lock<std::mutex> lock(m);
    cv.wait(lock, [&] { return holding; });
  }
  for (int64_t e = 0; e < 6; ++e) cache.get(e);
  EXPECT_EQ(cache.residentBlocks(), 1u);  // 2000 - 1408 leaves room for one 500 B model
  {
    std::lock_guard<std::mutex> lock(m);
    done = true;
  }
  cv.notify_all();
  decoder.join();  // its scratch is freed with it
  EXPECT_EQ(threadScratchBytes(), 0u);
  for (int64_t e = 0; e < 6; ++e) cache.get(e);
  EXPECT_EQ(cache.residentBlocks(), 4u);
  EXPECT_EQ(cache.residentBytes(), 2000u);
}

TEST(Cache, PrefetchNeverEvictsPinnedBlocks) {
  auto file = smallFile();
  LruCache cache(file, CacheBudget{0, 2});
  cache.get(0);
  cache.get(1);
  cache.setPinned({0, 1});
  EXPECT_FALSE(cache.prefetch(5));  // not read: only pinned blocks to evict
  EXPECT_EQ(cache.stats().blocksRead, 2u);
  EXPECT_TRUE(cache.contains(0));
  EXPECT_TRUE(cache.contains(1));
  EXPECT_FALSE(cache.contains(5));
  EXPECT_EQ(cache.stats().prefetchDropped, 1u);
  cache.setPinned({0});
  cache.prefetch(5);
  EXPECT_TRUE(cache.contains(0));
  EXPECT_FALSE(cache.contains(1));
  EXPECT_TRUE(cache.contains(5));
}

TEST(Cache, BandwidthCapLimitsThroughput) {
  auto file = smallFile();
  LruCache cache(file, CacheBudget{});
  const uint64_t bytes = 20 * file->entries()[0].size;  // 10 kB
  cache.setBandwidthCap(200e3);                         // 200 kB/s -> >= 50 ms
  const auto t0 = std::chrono::steady_clock::now();
  for (int64_t e = 0; e < 20; ++e) cache.get(e);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_GE(s, double(bytes) / 200e3 * 0.95);
  EXPECT_GT(cache.stats().throttleSeconds, 0.0);
  cache.dropOsCache();  // must not fail without root
}

TEST(Prefetch, StopsWhenTheFrameEnds) {
  auto file = smallFile();
  LruCache cache(file, CacheBudget{});
  cache.setBandwidthCap(50e3);  // 500 B blocks -> 10 ms each; all blocks would take > 5 s
  Prefetcher pf;
  std::vector<int64_t> all(file->entries().size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = int64_t(i);
  pf.start(Prefetcher::loadJob(cache, all));
  std::this_thread::sleep_for(std::chrono::milliseconds(60));
  const auto t0 = std::chrono::steady_clock::now();
  pf.finish();
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(ms, 100.0);  // at most about one block load (10 ms) after the flag
  EXPECT_FALSE(pf.busy());
  const uint64_t loaded = cache.stats().prefetchLoads;
  EXPECT_GT(loaded, 0u);
  EXPECT_LT(loaded, all.size());
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  EXPECT_EQ(cache.stats().prefetchLoads, loaded);  // nothing more after finish()
}

TEST(Prefetch, PredictorsAndNames) {
  EXPECT_EQ(std::string(makePrefetchPredictor("none")->name()), "none");
  EXPECT_EQ(std::string(makePrefetchPredictor("linear")->name()), "linear");
  EXPECT_THROW(makePrefetchPredictor("bogus"), InvalidArgument);
  EXPECT_EQ(predictorNames().size(), 5u);
  const auto lp = makePrefetchPredictor("linear");
  std::vector<Camera> h = {Camera::fromPose({1.5, 30, 10}, 8, 8),
                           Camera::fromPose({1.5, 30, 12}, 8, 8)};
  Camera next;
  ASSERT_TRUE(lp->predict(h, next));
  const Camera expect = Camera::fromPose({1.5, 30, 14}, 8, 8);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(next.eye[a], expect.eye[a], 2e-3);
  EXPECT_FALSE(makePrefetchPredictor("none")->predict(h, next));
  std::vector<int64_t> entries;
  EXPECT_FALSE(lp->predictEntries(h, entries));
}
