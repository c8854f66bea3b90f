// SPDX-License-Identifier: BSD-3-Clause
// BlockLoader: a frame's misses loaded by a pool of threads into the cache, frames before
// prefetching, a deadline that returns what has not arrived, damage recorded, not thrown.
#include <gtest/gtest.h>

#include <unistd.h>

#include <numeric>

#include "afam/render/block_loader.hpp"
#include "damaged_copy.hpp"
#include "render_test_util.hpp"

using namespace afam;
using Clock = std::chrono::steady_clock;

namespace {

std::shared_ptr<const AfamFile> smallFile() {
  return afam_test::encodeMl(33, EncodingMode::Fixed, 3, 4, 1e-3, 5);  // 5^3 floats = 500 B each
}

std::vector<int64_t> firstEntries(int64_t n) {
  std::vector<int64_t> v(static_cast<size_t>(n));
  std::iota(v.begin(), v.end(), 0);
  return v;
}

}  // namespace

TEST(BlockLoader, LoadsEveryRequestedBlockOnce) {
  auto file = smallFile();
  LruCache cache(file, CacheBudget{});
  BlockLoader loader(cache, 3);
  const std::vector<int64_t> want = firstEntries(int64_t(file->entries().size()));
  loader.request(want, LruCache::Purpose::Frame);
  loader.request(want, LruCache::Purpose::Frame);  // queued or loading: not twice
  EXPECT_EQ(loader.waitFor(want, Clock::time_point::max()), 0u);
  for (int64_t e : want) EXPECT_TRUE(cache.contains(e)) << e;
  EXPECT_EQ(cache.stats().blocksRead, want.size());
  EXPECT_EQ(loader.stats().frameLoads, want.size());
  loader.request(want, LruCache::Purpose::Frame);  // resident: nothing to do
  EXPECT_EQ(loader.waitFor(want, Clock::time_point::max()), 0u);
  EXPECT_EQ(cache.stats().blocksRead, want.size());
}

TEST(BlockLoader, ADeadlineReturnsWhatHasNotArrivedAndTheLoadsGoOn) {
  auto file = smallFile();
  LruCache cache(file, CacheBudget{});
  cache.setBandwidthCap(20000);  // 500-byte payloads: 25 ms each
  BlockLoader loader(cache, 1);
  const std::vector<int64_t> want = firstEntries(8);
  loader.request(want, LruCache::Purpose::Frame);
  const auto t0 = Clock::now();
  const size_t left = loader.waitFor(want, t0 + std::chrono::milliseconds(60));
  EXPECT_LT(Clock::now() - t0, std::chrono::seconds(1)) << "returned at the deadline";
  EXPECT_GE(left, 4u) << "8 loads of 25 ms cannot all arrive in 60 ms";
  EXPECT_EQ(loader.waitFor(want, Clock::time_point::max()), 0u);
  for (int64_t e : want) EXPECT_TRUE(cache.contains(e));
}

TEST(BlockLoader, FramesGoBeforePrefetchingWhichCanBeCancelled) {
  auto file = smallFile();
  LruCache cache(file, CacheBudget{});
  cache.setBandwidthCap(50000);  // 10 ms a payload
  BlockLoader loader(cache, 1);
  const std::vector<int64_t> prefetch = firstEntries(20);
  const std::vector<int64_t> frame{40, 41};
  loader.request(prefetch, LruCache::Purpose::Prefetch);
  loader.request(frame, LruCache::Purpose::Frame);
  EXPECT_EQ(loader.waitFor(frame, Clock::time_point::max()), 0u);
  EXPECT_GE(loader.waitFor(prefetch, Clock::now()), 15u) << "the frame's blocks came first";
  loader.cancelPrefetch();
  EXPECT_LE(loader.waitFor(prefetch, Clock::time_point::max()), 0u);
  size_t resident = 0;
  for (int64_t e : prefetch) resident += cache.contains(e) ? 1 : 0;
  EXPECT_LE(resident, 5u) << "cancelled prefetch requests were not loaded";
  EXPECT_EQ(loader.stats().frameLoads, 2u);
}

TEST(BlockLoader, ADamagedBlockIsRecordedNotThrown) {
  auto file = smallFile();
  auto damaged = afam_test::damagedCopy(*file, afam_test::tempPath("loader_damaged.afam"), {3});
  LruCache cache(damaged, CacheBudget{});
  BlockLoader loader(cache, 2);
  loader.request({2, 3, 4}, LruCache::Purpose::Frame);
  EXPECT_EQ(loader.waitFor({2, 3, 4}, Clock::time_point::max()), 0u);
  EXPECT_TRUE(cache.contains(2));
  EXPECT_FALSE(cache.contains(3));
  EXPECT_TRUE(cache.isDamaged(3));
  EXPECT_TRUE(loader.takeErrors().empty());
}

TEST(BlockLoader, AFailedLoadIsKeptAsAMessageAndTheBlockIsNotResident) {
  auto file = smallFile();
  const std::string path = afam_test::tempPath("loader_truncated.afam");
  auto copy = afam_test::damagedCopy(*file, path, {});  // an intact copy, opened
  LruCache cache(copy, CacheBudget{});
  BlockLoader loader(cache, 2);
  ASSERT_EQ(::truncate(path.c_str(), off_t(copy->payloadOffset())), 0);  // changed on disk
  loader.request({0, 1}, LruCache::Purpose::Frame);
  EXPECT_EQ(loader.waitFor({0, 1}, Clock::time_point::max()), 0u);
  EXPECT_FALSE(cache.contains(0));
  const std::vector<std::string> errors = loader.takeErrors();
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_NE(errors[0].find(path), std::string::npos) << errors[0];
  EXPECT_TRUE(loader.takeErrors().empty()) << "each message is handed out once";
  EXPECT_EQ(loader.stats().failed, 2u);
}
