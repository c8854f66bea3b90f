// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <cstring>
#include <thread>

#include "afam/base/huge_pages.hpp"
#include "afam/base/thread_scratch.hpp"

using namespace afam;

TEST(ThreadScratch, SlotsKeepTheirContentsAndAreCountedUntilReleased) {
  releaseAllThreadScratch();  // what tests before this one left on this thread
  const uint64_t before = threadScratchBytes();
  ASSERT_EQ(before, 0u);  // no other thread holds any
  auto* small = threadScratch<uint8_t>(ScratchSlot::Frame, 1000);
  auto* large = threadScratch<float>(ScratchSlot::Residual, 300000);  // 1.2 MB: on huge pages
  std::memset(small, 7, 1000);
  large[299999] = 2.5f;
  EXPECT_EQ(reinterpret_cast<uintptr_t>(small) % 64, 0u);
  // What each holds: the small slot in 64-byte lines, the large one in whole huge pages.
  EXPECT_EQ(threadScratchBytes() - before, 1024u + kHugePageBytes);
#if defined(__linux__)
  EXPECT_EQ(reinterpret_cast<uintptr_t>(large) % kHugePageBytes, 0u);
#endif
  // A slot between 64 kB and 1 MB is mapped in ordinary pages.
  threadScratch<uint8_t>(ScratchSlot::Stored, 100000);
  EXPECT_EQ(threadScratchBytes() - before, 1024u + kHugePageBytes + 102400u);
  // One whose pages come to 1 MB is mapped, and counted, as a huge page.
  threadScratch<uint8_t>(ScratchSlot::ChainStored, (size_t(1) << 20) - 100);
  EXPECT_EQ(threadScratchBytes() - before, 1024u + 2 * kHugePageBytes + 102400u);
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
  releaseThreadScratch();  // the large slots go, the small one stays
  EXPECT_EQ(threadScratchBytes() - before, 1024u);
  EXPECT_EQ(threadScratch<uint8_t>(ScratchSlot::Frame, 10), small);
  releaseAllThreadScratch();  // the small one too
  EXPECT_EQ(threadScratchBytes(), before);
}

TEST(HugePages, LargeBuffersAreAlignedToAHugePageAndKeepTheirValuesAsTheyGrow) {
  HugePageVector<double> small(1000, 1.5), large(300000);  // 8 kB, 2.4 MB
  for (size_t i = 0; i < large.size(); ++i) large[i] = double(i);
#if defined(__linux__)
  EXPECT_EQ(reinterpret_cast<uintptr_t>(large.data()) % kHugePageBytes, 0u);
#endif
  large.resize(700000, -1.0);  // 5.6 MB: a new mapping, the values copied over
  small.resize(200000, 2.5);   // from operator new to a mapping
  for (size_t i = 0; i < 300000; ++i) ASSERT_EQ(large[i], double(i));
  EXPECT_EQ(large[699999], -1.0);
  EXPECT_EQ(small[999], 1.5);
  EXPECT_EQ(small[199999], 2.5);
}
