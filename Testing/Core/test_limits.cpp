// SPDX-License-Identifier: BSD-3-Clause
// Limits held while replaying: with a cache budget of N bytes the cache never holds more than N
// bytes, at any moment of any frame, prefetch included (FrameStats::cachePeakBytes).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "afam/base/thread_scratch.hpp"
#include "afam/render/renderer.hpp"
#include "afam/scene/camera.hpp"
#include "render_test_util.hpp"

using namespace afam;

TEST(Limits, ReplayKeepsTheCacheWithinItsByteBudgetAtEveryFrame) {
  releaseAllThreadScratch();  // the budget counts scratch; tests before this one left some here
  const auto file = afam_test::encodeMl(65, EncodingMode::Adaptive, 3, 4, 1e-4);
  uint64_t total = 0;
  for (const ModelEntry& e : file->entries()) total += e.size;
  for (const std::string prefetch : {"none", "linear"}) {
    RenderOptions o;
    o.threads = 2;
    o.prefetch = prefetch;
    o.cache = CacheBudget{total / 5, 0};  // a fifth of the file: frames must evict
    Renderer renderer(file, o);
    uint64_t largest = 0;
    for (int i = 0; i < 36; ++i) {
      const Pose pose{1.1 + 0.02 * (i % 7), 10.0 * i, 15.0 - i};
      FrameStats st;
      renderer.renderFrame(Camera::fromPose(pose, 24, 24), st);
      ASSERT_LE(st.cachePeakBytes, o.cache.bytes) << "frame " << i << ", prefetch " << prefetch;
      ASSERT_LE(st.cacheBytes, st.cachePeakBytes) << "frame " << i;
      largest = std::max(largest, st.cachePeakBytes);
    }
    const CacheStats cs = renderer.cache().stats();
    std::printf(
        "[limits] prefetch=%s budget=%llu of %llu file bytes: largest frame peak %llu, %llu "
        "evictions\n",
        prefetch.c_str(), (unsigned long long)o.cache.bytes, (unsigned long long)total,
        (unsigned long long)largest, (unsigned long long)cs.evictions);
    EXPECT_GT(cs.evictions, 0u) << "the budget never bound: the test proves nothing";
    EXPECT_GT(largest, o.cache.bytes / 2) << "the cache never filled half its budget";
  }
}
