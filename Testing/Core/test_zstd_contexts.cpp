// SPDX-License-Identifier: BSD-3-Clause
// The thread's zstd contexts (entropy/zstd_contexts.hpp): frames whose tables take megabytes (their
// memory on huge pages through a custom allocator) compress and decompress as with zstd's own
// contexts, the same bytes, on every thread, each thread with contexts of its own.
#include <gtest/gtest.h>
#include <zstd.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <thread>
#include <vector>

#include "afam/entropy/zstd_contexts.hpp"

using namespace afam;

namespace {

/// Bytes like a noisy block's varints: mostly small codes, runs of zeros.
std::vector<uint8_t> varintLike(size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::geometric_distribution<int> code(0.6);
  std::bernoulli_distribution zeroRun(0.02);
  std::vector<uint8_t> out(n);
  for (size_t i = 0; i < n;) {
    if (zeroRun(rng)) {
      for (size_t e = std::min(n, i + 200); i < e; ++i) out[i] = 0;
    } else {
      out[i++] = uint8_t(std::min(code(rng), 127));
    }
  }
  return out;
}

std::vector<uint8_t> compressWith(ZSTD_CCtx* ctx, const std::vector<uint8_t>& src, int level) {
  std::vector<uint8_t> out(ZSTD_compressBound(src.size()));
  const size_t z = ZSTD_compressCCtx(ctx, out.data(), out.size(), src.data(), src.size(), level);
  EXPECT_FALSE(ZSTD_isError(z)) << ZSTD_getErrorName(z);
  out.resize(ZSTD_isError(z) ? 0 : z);
  return out;
}

}  // namespace

TEST(ZstdContexts, LargeTablesGiveZstdsOwnBytesOnEveryThread) {
  // 600 kB at level 15: 17 MB of tables; then 20 kB at level 1 and 600 kB at level 12 on the
  // same context (its workspace resized between them).
  const std::vector<uint8_t> big = varintLike(600000, 3), small = varintLike(20000, 4);
  ZSTD_CCtx* own = ZSTD_createCCtx();
  const std::vector<uint8_t> want15 = compressWith(own, big, 15),
                             want1 = compressWith(own, small, 1),
                             want12 = compressWith(own, big, 12);
  ZSTD_freeCCtx(own);
  auto check = [&]() -> ZSTD_CCtx* {
    ZSTD_CCtx* c = threadCCtx();
    EXPECT_EQ(threadCCtx(), c);  // kept between frames
    EXPECT_EQ(compressWith(c, big, 15), want15);
    EXPECT_EQ(compressWith(c, small, 1), want1);
    const std::vector<uint8_t> z12 = compressWith(c, big, 12);
    EXPECT_EQ(z12, want12);
    std::vector<uint8_t> back(big.size());
    const size_t got =
        ZSTD_decompressDCtx(threadDCtx(), back.data(), back.size(), z12.data(), z12.size());
    EXPECT_FALSE(ZSTD_isError(got)) << ZSTD_getErrorName(got);
    EXPECT_EQ(got, big.size());
    EXPECT_EQ(back, big);
    return c;
  };
  ZSTD_CCtx* mine = check();
  ZSTD_CCtx* other = nullptr;
  std::thread t([&] { other = check(); });
  t.join();
  EXPECT_NE(other, mine);
  EXPECT_LT(want15.size(), big.size() / 2);  // the input compresses: the tables were used
}
