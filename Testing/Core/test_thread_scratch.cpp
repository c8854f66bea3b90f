// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <cstring>
#include <thread>

#include "afam/base/thread_scratch.hpp"

using namespace afam;

TEST(ThreadScratch, SlotsKeepTheirContentsAndAreCountedUntilReleased) {
  releaseAllThreadScratch();  // what tests before this one left on this thread
  const uint64_t before = threadScratchBytes();
  ASSERT_EQ(before, 0u);  // no other thread holds any
  auto* small = threadScratch<uint8_t>(ScratchSlot::Frame, 1000);
  auto* large = threadScratch<float>(ScratchSlot::Residual, 300000);  // 1.2 MB: mapped
  std::memset(small, 7, 1000);
  large[299999] = 2.5f;
  EXPECT_EQ(reinterpret_cast<uintptr_t>(small) % 64, 0u);
  EXPECT_GE(threadScratchBytes() - before, 1000u + 1200000u);
  EXPECT_LT(threadScratchBytes() - before, 1000u + 1200000u + 2 * 65536u);
  // Asking again for no more returns the same memory, contents kept.
  EXPECT_EQ(threadScratch<uint8_t>(ScratchSlot::Frame, 10), small);
  EXPECT_EQ(small[999], 7);
  EXPECT_EQ(threadScratch<float>(ScratchSlot::Residual, 300000)[299999], 2.5f);
  // Another thread's slots are its own, and counted while it holds them.
  uint64_t during = 0;
  std::thread other([&] {
    EXPECT_NE(threadScratch<uint8_t>(ScratchSlot::Frame, 1000), small);
    during = threadScratchBytes();
  });  // freed when the thread ends
  other.join();
  EXPECT_GE(during, threadScratchBytes() + 1000u);
  releaseThreadScratch();  // the large slot goes, the small one stays
  EXPECT_EQ(threadScratchBytes() - before, 1024u);
  EXPECT_EQ(threadScratch<uint8_t>(ScratchSlot::Frame, 10), small);
  releaseAllThreadScratch();  // the small one too
  EXPECT_EQ(threadScratchBytes(), before);
}
