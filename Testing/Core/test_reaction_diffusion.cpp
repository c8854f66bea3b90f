// SPDX-License-Identifier: BSD-3-Clause
// The Gray-Scott generator: the same values on one thread and on several (the planes of an
// iteration are shared out; each reads only the iteration before), and patterns that grow.
#include <gtest/gtest.h>

#include <algorithm>

#include "afam/volume/reaction_diffusion.hpp"

using namespace afam;

TEST(GrayScott, ThreadsGiveTheSameValuesBitForBit) {
  GrayScottOptions o;
  o.dims = {128, 128, 64};  // 2^20 cells: large enough to be shared out
  o.threads = 1;
  GrayScott one(o);
  o.threads = 3;
  GrayScott three(o);
  one.advance(12);
  three.advance(12);
  EXPECT_EQ(one.v(), three.v());
  const auto mm = std::minmax_element(one.v().begin(), one.v().end());
  EXPECT_GT(*mm.second, 0.1f) << "the seeds are there";
  EXPECT_EQ(*mm.first, 0.0f) << "far from the seeds nothing grew yet";
}
