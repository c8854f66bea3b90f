// SPDX-License-Identifier: BSD-3-Clause
// SlotCache (base/slot_cache.hpp): a slot answers only for the key its value was made for, a
// value the budget has no room for is not kept, replacing a slot's value frees its bytes, and
// threads filling their own slots at once never take it over its budget.
#include <gtest/gtest.h>

#include <thread>
#include <vector>

#include "afam/base/slot_cache.hpp"

using afam::SlotCache;

TEST(SlotCache, ASlotAnswersForItsKeyWithinTheBudget) {
  SlotCache c;
  c.reset(3, 10 * sizeof(float));
  std::vector<float> out{7};
  EXPECT_FALSE(c.find(0, 5, out));
  EXPECT_EQ(out, std::vector<float>{7}) << "a miss leaves the output alone";
  c.put(0, 5, std::vector<float>(6, 1.5f));
  ASSERT_TRUE(c.find(0, 5, out));
  EXPECT_EQ(out, std::vector<float>(6, 1.5f));
  EXPECT_FALSE(c.find(0, 6, out)) << "another key";
  EXPECT_FALSE(c.find(1, 5, out)) << "another slot";
  c.put(1, 5, std::vector<float>(5, 2.0f));  // 6 + 5 floats: over the budget of 10
  EXPECT_FALSE(c.find(1, 5, out));
  EXPECT_EQ(c.bytes(), 6 * sizeof(float));
  c.put(0, 9, std::vector<float>(2, 3.0f));  // replaces slot 0's value, freeing its bytes
  EXPECT_FALSE(c.find(0, 5, out));
  EXPECT_EQ(c.bytes(), 2 * sizeof(float));
  c.put(1, 5, std::vector<float>(5, 2.0f));
  ASSERT_TRUE(c.find(1, 5, out));
  EXPECT_EQ(out, std::vector<float>(5, 2.0f));
  EXPECT_EQ(c.bytes(), 7 * sizeof(float));
}

TEST(SlotCache, ThreadsFillingTheirSlotsNeverPassTheBudget) {
  constexpr int kThreads = 4, kSlotsEach = 64, kFloats = 100;
  SlotCache c;
  c.reset(kThreads * kSlotsEach, 50 * kFloats * sizeof(float));  // room for 50 of 256 values
  std::vector<std::thread> threads;
  std::vector<int> kept(kThreads, 0);
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      std::vector<float> out;
      for (int round = 0; round < 3; ++round)
        for (int k = 0; k < kSlotsEach; ++k) {
          const size_t slot = size_t(t * kSlotsEach + k);
          c.put(slot, uint64_t(round), std::vector<float>(kFloats, float(slot)));
          if (round == 2 && c.find(slot, 2, out)) {
            EXPECT_EQ(out[0], float(slot));
            ++kept[size_t(t)];
          }
        }
    });
  for (std::thread& t : threads) t.join();
  int total = 0;
  for (int k : kept) total += k;
  EXPECT_LE(c.bytes(), 50u * kFloats * sizeof(float));
  EXPECT_EQ(c.bytes(), size_t(total) * kFloats * sizeof(float));
  EXPECT_GT(total, 0);
}
