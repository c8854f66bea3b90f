// SPDX-License-Identifier: BSD-3-Clause
// A frame never waits longer than its budget (issue 44): resident coarsest levels, stand-ins from
// the nearest intact resident ancestor, loads by importance, a cache under pressure that does not
// thrash. Slow storage is a load hook that blocks reads until the test opens it: no wall-clock
// race decides a result.
#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <numeric>

#include "afam/render/block_loader.hpp"
#include "afam/render/frame_budget.hpp"
#include "afam/render/renderer.hpp"
#include "damaged_copy.hpp"
#include "render_test_util.hpp"

using namespace afam;
using Clock = std::chrono::steady_clock;

namespace {

/// Reads of levels >= `from` wait until open() (a storage that does not answer in time).
class Gate {
 public:
  explicit Gate(int from) : from_(from) {}
  void hold(const AfamFile& f, int64_t entry) {
    if (f.entries()[size_t(entry)].level < from_) return;
    std::unique_lock<std::mutex> lock(mutex_);
    opened_.wait(lock, [this] { return open_; });
  }
  void open() {
    std::lock_guard<std::mutex> lock(mutex_);
    open_ = true;
    opened_.notify_all();
  }

 private:
  int from_;
  std::mutex mutex_;
  std::condition_variable opened_;
  bool open_ = false;
};

/// Opens the gate when it goes out of scope (before the renderer whose loads it holds).
struct OpenAtEnd {
  Gate& gate;
  ~OpenAtEnd() { gate.open(); }
};

std::shared_ptr<const AfamFile> mlFile() {
  return afam_test::encodeMl(65, EncodingMode::Adaptive, 3, 8, 1e-3);
}

RenderOptions options() {
  RenderOptions o;
  o.threads = 2;
  o.loadThreads = 2;
  o.sampleDistance = 0.01f;
  o.cache = CacheBudget{};
  return o;
}

Camera camera() { return Camera::lookAt({1.1, 1.3, 0.9}, {0, 0, 0}, {0, 0, 1}, 60, 48, 48); }

FrameSettings finest(const Renderer& r, double budgetMs) {
  FrameSettings s = r.settings();
  s.lod.forceLevel = r.file().partition().levels() - 1;
  s.missBudgetMs = budgetMs;
  return s;
}

/// The blocks of the finest selection that hold a model.
std::vector<BlockRef> drawn(Renderer& r, const Camera& c) {
  r.setFrameSettings(finest(r, -1));
  std::vector<BlockRef> out;
  for (const BlockRef& b : r.select(c).visible)
    if (r.file().entries()[size_t(b.entry)].kind != BlockKind::Empty) out.push_back(b);
  return out;
}

}  // namespace

TEST(ResidentLevels, AsManyCoarseLevelsAsFitAShareOfTheBudgets) {
  const auto file = mlFile();                                 // levels of 2^3, 4^3 and 8^3 blocks
  EXPECT_EQ(residentLevels(*file, CacheBudget{}).levels, 1);  // 72 of 584 blocks > 1/16
  EXPECT_EQ(residentLevels(*file, CacheBudget{0, 200}).levels, 1);
  uint64_t coarseBytes = 0, coarseBlocks = 0;  // of levels 0 and 1
  for (const ModelEntry& e : file->entries())
    if (e.level < 2 && e.kind != BlockKind::Empty) {
      coarseBytes += e.size;
      coarseBlocks++;
    }
  EXPECT_EQ(residentLevels(*file, CacheBudget{coarseBytes * 16, coarseBlocks * 16}).levels, 2);
  EXPECT_EQ(residentLevels(*file, CacheBudget{coarseBytes * 16 - 16, coarseBlocks * 16}).levels, 1);
  EXPECT_EQ(residentLevels(*file, CacheBudget{0, 16}).levels, 1);  // level 0 fits half
  EXPECT_EQ(residentLevels(*file, CacheBudget{0, 15}).levels, 0);
  const ResidentLevels one = residentLevels(*file, CacheBudget{});
  uint64_t bytes = 0;
  for (const int64_t e : one.entries) {
    EXPECT_EQ(file->entries()[size_t(e)].level, 0);
    bytes += file->entries()[size_t(e)].size;
  }
  EXPECT_EQ(one.bytes, bytes);
  EXPECT_GT(one.entries.size(), 0u);
  EXPECT_EQ(residentLevels(*file, CacheBudget{one.bytes * 16, 0}).levels, 1);
  EXPECT_EQ(residentLevels(*file, CacheBudget{one.bytes * 2 - 1, 0}).levels, 0);
}

TEST(FrameBudget, ASlowLoaderNeverHoldsAFrameAndStandInsAreReported) {
  const auto file = mlFile();
  Gate gate(1);  // everything finer than level 0 waits for the test
  Renderer r(file, options());
  OpenAtEnd openAtEnd{gate};
  r.cache().setLoadHook([&gate](const AfamFile& f, int64_t e) { gate.hold(f, e); });
  const Camera c = camera();
  const std::vector<BlockRef> blocks = drawn(r, c);
  uint64_t bytes = 0;
  for (const BlockRef& b : blocks) bytes += file->entries()[size_t(b.entry)].size;
  FrameStats st;
  const FrameSettings budgeted = finest(r, 20);
  r.renderFrame(c, budgeted, st);
  EXPECT_EQ(st.residentLevels, 1);
  EXPECT_EQ(st.standInBlocks, int64_t(blocks.size())) << "every finest block is behind";
  EXPECT_EQ(st.blocksBehind, int64_t(blocks.size()));
  EXPECT_EQ(st.bytesBehind, bytes);
  EXPECT_LE(st.slots, 8) << "drawn from level 0";
  EXPECT_GT(st.slots, 0);
  EXPECT_LT(st.cachingMs - st.residentLoadMs, 20 + 2000) << "the frame waited for its misses";
  FrameStats again;  // the loads still blocked: the next frame does not wait for them either
  r.renderFrame(c, finest(r, 0), again);
  EXPECT_EQ(again.residentLevels, 1);
  EXPECT_EQ(again.residentLoadMs, 0);
  EXPECT_EQ(again.standInBlocks, int64_t(blocks.size()));
  EXPECT_EQ(again.bytesRead, 0u);

  gate.open();
  ASSERT_TRUE(r.loader().waitIdle(Clock::now() + std::chrono::seconds(60)));
  r.renderFrame(c, budgeted, st);  // refined: what loaded after the frames is drawn
  EXPECT_EQ(st.standInBlocks, 0);
  EXPECT_EQ(st.blocksBehind, 0);
}

TEST(FrameBudget, ABudgetOfZeroDrawsWhatIsResidentAndTheStillFrameIsExact) {
  const auto file = mlFile();
  Gate gate(1);
  Renderer r(file, options());
  OpenAtEnd openAtEnd{gate};
  r.cache().setLoadHook([&gate](const AfamFile& f, int64_t e) { gate.hold(f, e); });
  const Camera c = camera();
  FrameStats st;
  r.renderFrame(c, finest(r, 0), st);
  EXPECT_EQ(st.standInBlocks, int64_t(drawn(r, c).size()));
  gate.open();
  const ImageRGBA still = r.renderFrame(c, finest(r, -1), st);
  EXPECT_EQ(st.standInBlocks, 0);
  EXPECT_EQ(st.blocksBehind, 0);
  Renderer fresh(file, options());
  FrameStats st2;
  const ImageRGBA want = fresh.renderFrame(c, finest(fresh, -1), st2);
  EXPECT_EQ(still.rgba, want.rgba);
}

TEST(FrameBudget, ACacheUnderPressureKeepsTheFramesBlocksAndDoesNotThrash) {
  const auto file = mlFile();
  RenderOptions o = options();
  Renderer probe(file, o);
  const Camera c = camera();
  const int64_t visible = int64_t(drawn(probe, c).size());
  ASSERT_GT(visible, 40);
  const uint64_t blocks = uint64_t(visible / 2);  // half the frame's finest blocks fit
  o.cache = CacheBudget{0, blocks};
  Renderer r(file, o);
  FrameStats st;
  const FrameSettings s = finest(r, 60000);  // waits until every load has been tried
  r.renderFrame(c, s, st);
  EXPECT_EQ(st.residentLevels, 1);
  const int64_t kept = int64_t(residentLevels(*file, o.cache).entries.size());
  EXPECT_EQ(st.standInBlocks, visible - (int64_t(blocks) - kept)) << "the rest coarsened";
  EXPECT_LE(r.cache().residentBlocks(), blocks);
  const CacheStats before = r.cache().stats();
  FrameStats second;
  r.renderFrame(c, s, second);
  EXPECT_EQ(second.bytesRead, 0u) << "nothing evicted and read again";
  EXPECT_EQ(r.cache().stats().evictions, before.evictions);
  EXPECT_EQ(second.standInBlocks, st.standInBlocks);
  for (const int64_t e : residentLevels(*file, o.cache).entries)
    EXPECT_TRUE(r.cache().contains(e)) << "resident level entry " << e;
}

TEST(FrameBudget, ADamagedStandInIsReplacedByTheNextIntactAncestorReportedOnce) {
  const auto intact = mlFile();
  int64_t bad = -1;  // a level-0 model with bytes to damage
  for (int64_t i = 0; i < int64_t(intact->entries().size()) && bad < 0; ++i)
    if (intact->entries()[size_t(i)].level == 0 && intact->entries()[size_t(i)].storedSize >= 8)
      bad = i;
  ASSERT_GE(bad, 0);
  const auto file =
      afam_test::damagedCopy(*intact, afam_test::tempPath("frame_budget_damaged"), {bad});
  Gate gate(1);
  Renderer r(file, options());
  OpenAtEnd openAtEnd{gate};
  r.cache().setLoadHook([&gate](const AfamFile& f, int64_t e) { gate.hold(f, e); });
  const Camera c = camera();
  int64_t under = 0;  // finest blocks whose level-0 ancestor is the damaged one
  const std::vector<BlockRef> blocks = drawn(r, c);
  const Int3 b0 = file->entries()[size_t(bad)].block;
  const int stride = file->partition().stride(0);
  for (const BlockRef& b : blocks)
    under +=
        (b.ijk[0] / stride == b0[0] && b.ijk[1] / stride == b0[1] && b.ijk[2] / stride == b0[2])
            ? 1
            : 0;
  FrameStats st;
  r.renderFrame(c, finest(r, 20), st);
  EXPECT_EQ(st.damageReports.size(), 1u);
  EXPECT_EQ(st.blocksBehind, int64_t(blocks.size()));
  EXPECT_EQ(st.standInBlocks, int64_t(blocks.size()) - under);
  r.renderFrame(c, finest(r, 20), st);
  EXPECT_TRUE(st.damageReports.empty()) << "reported once";
}

TEST(BlockLoader, ANewFrameDropsTheRequestsOfEarlierFramesNotStarted) {
  const auto file = mlFile();
  LruCache cache(file, CacheBudget{});
  Gate gate(0);
  OpenAtEnd openAtEnd{gate};
  cache.setLoadHook([&gate](const AfamFile& f, int64_t e) { gate.hold(f, e); });
  {
    BlockLoader loader(cache, 1);
    OpenAtEnd openFirst{gate};
    loader.requestFrame({0, 1, 2});
    loader.requestFrame({3, 1});
    EXPECT_FALSE(loader.pending(2)) << "dropped";
    EXPECT_TRUE(loader.pending(1));
    EXPECT_TRUE(loader.pending(3));
    gate.open();
    ASSERT_TRUE(loader.waitIdle(Clock::now() + std::chrono::seconds(60)));
  }
  EXPECT_TRUE(cache.contains(3));
  EXPECT_TRUE(cache.contains(1));
  EXPECT_FALSE(cache.contains(2));
}

TEST(LoadOrder, CentralLargeOpaqueBlocksFirst) {
  const auto file = mlFile();
  const Partition& p = file->partition();
  const int fine = p.levels() - 1;
  const Camera c = Camera::lookAt({0, 0, 3}, {0, 0, 0}, {0, 1, 0}, 30, 64, 64);
  auto at = [&](Int3 ijk) { return BlockRef{fine, ijk, file->entryIndex(fine, ijk)}; };
  const BlockRef centre = at({3, 3, 7}), corner = at({0, 0, 7}), far = at({3, 3, 0});
  const double ic = blockImportance(*file, c, centre, 1, {}, 0, 1);
  EXPECT_GT(ic, blockImportance(*file, c, corner, 1, {}, 0, 1));
  EXPECT_GT(ic, blockImportance(*file, c, far, 1, {}, 0, 1));
  EXPECT_DOUBLE_EQ(blockImportance(*file, c, centre, 2, {}, 0, 1), 2 * ic);
  EXPECT_EQ(blockImportance(*file, c, centre, 0, {}, 0, 1), 0.0);
  const std::vector<float> clear(4 * 16, 0.f);  // a transparent table adds nothing
  EXPECT_EQ(blockImportance(*file, c, centre, 1, clear, 0, 1), 0.0);
  const auto order = importanceOrder(
      *file, c, {far, corner, centre}, [](const BlockRef&) { return -1; }, {}, 0, 1);
  EXPECT_EQ(order.front(), centre.entry);
}
