// SPDX-License-Identifier: BSD-3-Clause
// afam replay FILE --trajectory T.dat [--size W,H] [--cache-blocks N | --cache-bytes B]
//   [--prefetch none|linear|appa|forecache|lstm] [--cold] [--storage-mbps R] [--csv OUT.csv]
//   [--steps FIRST:LAST] [--view K]
// Replays a recorded trajectory through the out-of-core renderer and reports, per point of view,
// caching time, rendering time, input latency, hits, misses, bytes read and culled blocks; the
// last line is  median_latency_ms=<x> median_caching_ms=<y> median_render_ms=<z> miss_rate=<m>.
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/eval/image_metrics.hpp"
#include "afam/eval/png_io.hpp"
#include "afam/ranks/rank_boxes.hpp"
#include "afam/render/renderer.hpp"
#include "afam/scene/camera.hpp"
#include "cli.hpp"
#include "commands.hpp"
#include "device_option.hpp"
#include "render_args.hpp"

using namespace afam;
using namespace afam::cli;

namespace {
double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// The q-quantile (nearest rank) of v; 0 for none.
double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t rank = size_t(std::ceil(q * double(v.size())));
  return v[std::min(v.size() - 1, rank > 0 ? rank - 1 : 0)];
}
/// `--steps FIRST:LAST`: which step each view draws, and moving the renderer there (keeping
/// what it holds) with the step after it in the direction of play as the next one.
class StepPlayback {
 public:
  StepPlayback(const std::string& path, const std::string& spec, const AfamFile& file)
      : path_(path) {
    if (spec.empty()) return;
    const size_t colon = spec.find(':');
    if (colon == std::string::npos)
      throw InvalidArgument("--steps wants FIRST:LAST, got \"" + spec + "\"");
    first_ = std::stoll(spec.substr(0, colon));
    last_ = std::stoll(spec.substr(colon + 1));
    const int64_t n = file.stepCount();
    if (first_ < 0 || last_ < 0 || first_ >= n || last_ >= n)
      throw InvalidArgument("--steps " + spec + " outside the " + std::to_string(n) + " steps of " +
                            path);
    active_ = true;
  }
  bool active() const { return active_; }
  /// The step view i draws.
  int64_t stepOf(size_t i) const {
    const int64_t span = std::llabs(last_ - first_) + 1, k = int64_t(i % size_t(span));
    return last_ >= first_ ? first_ + k : first_ - k;
  }
  std::shared_ptr<const AfamFile> open(size_t i) const { return AfamFile::open(path_, stepOf(i)); }
  /// Moves the renderer to view i's step (the file prefetched as the next one when it is that
  /// step) and names the step after it; returns the milliseconds spent opening steps.
  double moveTo(Renderer& renderer, size_t i) {
    const auto t0 = std::chrono::steady_clock::now();
    const int64_t s = stepOf(i);
    if (renderer.file().step() != s) {
      renderer.setStep(next_ && next_->step() == s ? next_ : AfamFile::open(path_, s));
    }
    const int64_t after = stepOf(i + 1);
    if (after != s && (!next_ || next_->step() != after)) next_ = AfamFile::open(path_, after);
    renderer.setNextStep(after != s ? next_ : nullptr);
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }

 private:
  std::string path_;
  int64_t first_ = 0, last_ = 0;
  bool active_ = false;
  std::shared_ptr<const AfamFile> next_;
};

struct RankOfRanks {
  int rank = 0, ranks = 1;
};

/// `--rank R/N`: 0 <= R < N (rankBox checks the pair again).
RankOfRanks parseRank(const std::string& text) {
  RankOfRanks r;
  char slash = 0;
  std::istringstream in(text);
  if (!(in >> r.rank >> slash >> r.ranks) || slash != '/' || !in.eof() || r.ranks < 1 ||
      r.rank < 0 || r.rank >= r.ranks)
    throw InvalidArgument("--rank must be R/N with 0 <= R < N, not '" + text + "'");
  return r;
}

/// `--ssim`: each frame's image against the exact frame of the same view, drawn by a second
/// renderer of the same file that waits for every block (unlimited cache, no prefetching), on the
/// same device (its own GPU pool), after the frame's timing.
class ExactReference {
 public:
  ExactReference(const std::shared_ptr<const AfamFile>& file, const RenderOptions& opts,
                 const std::string& device, long long gpuBudgetMiB) {
    RenderOptions exact = opts;
    exact.cache = CacheBudget{};
    exact.cold = false;
    exact.storageMBps = 0;
    exact.prefetch = "none";
    exact.missBudgetMs = -1;
    renderer_ = std::make_unique<Renderer>(file, exact);
    useDevice(*renderer_, device, gpuBudgetMiB);
  }
  double ssimOf(const ImageRGBA& image, const Camera& camera) {
    FrameStats st;
    FrameSettings s = renderer_->settings();
    return compare(toRGB8(image), toRGB8(renderer_->renderFrame(camera, s, st))).ssim;
  }

 private:
  std::unique_ptr<Renderer> renderer_;
};

}  // namespace

int runReplay(int argc, char** argv) {
  std::set<std::string> values = renderValueOptions();
  values.insert({"csv", "frames", "device", "gpu-budget-mb", "still-out", "steps", "view", "rank"});
  Args args(argc, argv, values, {"cold", "no-culling", "quiet", "ssim"});
  const char* usage =
      "afam replay FILE --trajectory T.dat [--size W,H] [--cache-blocks N | --cache-bytes B] "
      "[--prefetch none|linear|appa|forecache|lstm] [--cold] [--storage-mbps R] [--csv OUT.csv]";
  if (args.help()) {
    std::printf(
        "usage: %s\n\n"
        "Replays every point of view of a trajectory file (recorded, or from `afam trajectory`) "
        "through\n"
        "the out-of-core renderer on the CPU: LOD cut, culling, LRU cache, prefetch while the\n"
        "frame renders. The method follows FILE's mode (adaptive/inlevel = Adaptive-FAM,\n"
        "fixed = FAM, ds = downsampling). Caching time = LOD selection + cache lookups and reads "
        "+\n"
        "copying the frame's models; rendering time = ray casting; latency = their sum.\n"
        "--storage-mbps is an EMULATION of a slower storage tier (the paper used a 5400 rpm "
        "disk):\n"
        "reads are followed by a sleep so that bytes/time never exceed the cap.\n\n"
        "  --trajectory T.dat     trajectory file (required)\n"
        "  --csv OUT.csv          per point of view: "
        "pov,caching_ms,render_ms,latency_ms,hits,misses,\n"
        "                         "
        "bytes_read,visible_blocks,frustum_culled,tf_culled,prefetched_blocks,\n"
        "                         cache_bytes,cache_peak_bytes (resident in the cache at the end\n"
        "                         of the frame / at most during it; never above --cache-bytes),\n"
        "                         gpu_uploads (models the GPU pool took in), on_gpu (0: the\n"
        "                         frame was cast on the CPU), stand_ins, blocks_behind,\n"
        "                         bytes_behind, ssim (-1 without --ssim), select_ms and wait_ms\n"
        "                         (of caching_ms: the LOD cut, and the wait for the misses)\n"
        "  --frames N             replay only the first N points of view\n"
        "  --still-out IMG.png    after the path, render its last view once more waiting for\n"
        "                         every block (the still frame; also printed with\n"
        "                         --miss-budget-ms) and write it\n"
        "  --steps FIRST:LAST     a run's playback: view i draws step FIRST + i, back to FIRST\n"
        "                         after LAST (LAST < FIRST plays backwards); the renderer keeps\n"
        "                         its cache and GPU pool across steps and loads the next step's\n"
        "                         blocks of the view while a step is shown. Opening a step is\n"
        "                         part of its frame's caching time\n"
        "  --view K               every frame from the trajectory's point of view K (playback\n"
        "                         with a still camera); --frames sets how many (default: as many\n"
        "                         as the trajectory has)\n"
        "  --rank R/N             draw only rank R's box of N (sort-last rendering, as each of\n"
        "                         N pvbatch or pvserver ranks does): what that rank reads,\n"
        "                         caches and casts\n"
        "  --ssim                 each frame's SSIM against the exact frame of its view (a\n"
        "                         second renderer waiting for every block, on the same\n"
        "                         --device; not timed)\n"
        "                         CSV columns after on_gpu: stand_ins, blocks_behind,\n"
        "                         bytes_behind (blocks of the selection drawn from a coarser\n"
        "                         level or not at all: the miss budget ran out), ssim (-1\n"
        "                         without --ssim)\n"
        "  --quiet                no per-view lines on stdout\n%s%s",
        usage, renderOptionsHelp(), deviceOptionHelp());
    return 0;
  }
  args.expectPositional(1, usage);
  if (!args.has("trajectory"))
    throw InvalidArgument("--trajectory is required; usage: " + std::string(usage));
  const auto size = parseSize(args.str("size", "256,256"));
  RenderOptions opts = parseRenderOptions(args);
  auto poses = loadTrajectory(args.str("trajectory"));
  if (args.has("frames")) {
    const long long n = args.integer("frames", 0);
    if (n < 1) throw InvalidArgument("--frames must be >= 1");
    if (size_t(n) < poses.size()) poses.resize(size_t(n));
  }
  if (args.has("view")) {
    const long long k = args.integer("view", 0);
    if (k < 0 || size_t(k) >= poses.size())
      throw InvalidArgument("--view " + std::to_string(k) + " outside the trajectory's " +
                            std::to_string(poses.size()) + " points of view");
    const Pose still = poses[size_t(k)];
    std::fill(poses.begin(), poses.end(), still);
  }
  const std::string path = args.positional()[0];
  auto file = AfamFile::open(path, args.integer("step", 0));
  StepPlayback playback(path, args.str("steps", ""), *file);
  if (playback.active()) file = playback.open(0);
  const RankOfRanks rank = parseRank(args.str("rank", "0/1"));
  if (rank.ranks > 1) opts.box = rankBox(*file, rank.rank, rank.ranks);
  Renderer renderer(file, opts);
  const DeviceChoice device =
      useDevice(renderer, args.str("device", "cpu"), args.integer("gpu-budget-mb", 2048));
  std::ofstream csv;
  if (args.has("csv")) {
    csv.open(args.str("csv"));
    if (!csv) throw IoError("replay: cannot write " + args.str("csv"));
    csv << "pov,caching_ms,render_ms,latency_ms,hits,misses,bytes_read,visible_blocks,"
           "frustum_culled,tf_culled,prefetched_blocks,cache_bytes,cache_peak_bytes,gpu_uploads,"
           "on_gpu,stand_ins,blocks_behind,bytes_behind,ssim,select_ms,wait_ms\n";
  }
  const bool quiet = args.has("quiet");
  std::vector<double> lat, cach, rend, ssims;
  std::unique_ptr<ExactReference> reference;
  if (args.has("ssim"))
    reference = std::make_unique<ExactReference>(file, opts, args.str("device", "cpu"),
                                                 args.integer("gpu-budget-mb", 2048));
  int64_t behind = 0;
  uint64_t hits = 0, misses = 0, bytes = 0, cachePeak = 0, poolPeak = 0;
  int64_t standIns = 0;
  for (size_t i = 0; i < poses.size(); ++i) {
    FrameStats st;
    const double openMs = playback.active() ? playback.moveTo(renderer, i) : 0.0;
    const Camera camera = Camera::fromPose(poses[i], size.first, size.second);
    const ImageRGBA image = renderer.renderFrame(camera, st);
    const double ssim = reference ? reference->ssimOf(image, camera) : -1.0;
    if (reference) ssims.push_back(ssim);
    behind += st.blocksBehind;
    st.cachingMs += openMs;
    st.latencyMs += openMs;
    printDeviceMessages(st);
    for (const std::string& r : st.damageReports) std::fprintf(stderr, "warning: %s\n", r.c_str());
    for (const std::string& r : st.loadErrors) std::fprintf(stderr, "warning: %s\n", r.c_str());
    lat.push_back(st.latencyMs);
    cach.push_back(st.cachingMs);
    rend.push_back(st.renderMs);
    hits += st.hits;
    misses += st.misses;
    standIns += st.standInBlocks;
    bytes += st.bytesRead;
    cachePeak = std::max(cachePeak, st.cachePeakBytes);
    poolPeak = std::max(poolPeak, st.poolBytes);
    if (csv.is_open())
      csv << i << ',' << st.cachingMs << ',' << st.renderMs << ',' << st.latencyMs << ',' << st.hits
          << ',' << st.misses << ',' << st.bytesRead << ',' << st.slots << ','
          << st.culled.frustumBlocks << ',' << st.culled.tfBlocks << ',' << st.prefetchedBlocks
          << ',' << st.cacheBytes << ',' << st.cachePeakBytes << ',' << st.cast.modelsUploaded
          << ',' << int(st.cast.onGpu) << ',' << st.standInBlocks << ',' << st.blocksBehind << ','
          << st.bytesBehind << ',' << ssim << ',' << st.selectMs << ',' << st.waitMs << '\n';
    if (!quiet)
      std::printf(
          "pov=%zu step=%lld caching_ms=%.3f render_ms=%.3f latency_ms=%.3f hits=%llu "
          "misses=%llu bytes_read=%llu visible=%lld frustum_culled=%lld tf_culled=%lld "
          "stand_ins=%lld cache_bytes=%llu\n",
          i, (long long)renderer.file().step(), st.cachingMs, st.renderMs, st.latencyMs,
          (unsigned long long)st.hits, (unsigned long long)st.misses,
          (unsigned long long)st.bytesRead, (long long)st.slots, (long long)st.culled.frustumBlocks,
          (long long)st.culled.tfBlocks, (long long)st.standInBlocks,
          (unsigned long long)st.cacheBytes);
  }
  if ((opts.missBudgetMs >= 0 || args.has("still-out")) && !poses.empty()) {  // the still frame
    FrameSettings still = renderer.settings();
    still.missBudgetMs = -1;
    FrameStats st;
    const ImageRGBA image =
        renderer.renderFrame(Camera::fromPose(poses.back(), size.first, size.second), still, st);
    if (args.has("still-out")) writePng(args.str("still-out"), toRGB8(image));
    std::printf("still_frame caching_ms=%.3f latency_ms=%.3f stand_ins=%lld\n", st.cachingMs,
                st.latencyMs, (long long)st.standInBlocks);
  }
  if (csv.is_open() && !csv.good()) throw IoError("replay: writing " + args.str("csv") + " failed");
  const double missRate = hits + misses ? double(misses) / double(hits + misses) : 0.0;
  std::printf(
      "\nmethod=%s povs=%zu image=%dx%d cache_blocks=%llu cache_bytes=%llu prefetch=%s "
      "cold=%d storage_mbps=%g\n",
      modeName(file->header().mode), poses.size(), size.first, size.second,
      (unsigned long long)opts.cache.blocks, (unsigned long long)opts.cache.bytes,
      opts.prefetch.c_str(), opts.cold ? 1 : 0, opts.storageMBps);
  std::printf("device=%s%s%s\n", device.used.c_str(), device.description.empty() ? "" : " ",
              device.description.c_str());
  if (rank.ranks > 1) {
    const CellBox& b = *opts.box;
    std::printf("rank=%d ranks=%d box=[%d,%d)x[%d,%d)x[%d,%d) finest blocks\n", rank.rank,
                rank.ranks, b.lo[0], b.hi[0], b.lo[1], b.hi[1], b.lo[2], b.hi[2]);
  }
  std::printf("%-12s %10s\n", "median", "ms");
  std::printf("%-12s %10.3f\n%-12s %10.3f\n%-12s %10.3f\n", "latency", median(lat), "caching",
              median(cach), "rendering", median(rend));
  std::printf("hits=%llu misses=%llu bytes_read=%llu\n", (unsigned long long)hits,
              (unsigned long long)misses, (unsigned long long)bytes);
  std::printf(
      "median_latency_ms=%.3f median_caching_ms=%.3f median_render_ms=%.3f miss_rate=%.4f "
      "p95_latency_ms=%.3f stand_in_blocks=%lld\n",
      median(lat), median(cach), median(rend), missRate, percentile(lat, 0.95),
      (long long)standIns);
  // The budget's figures: the first image, the worst caching after it, the motion frames' SSIM.
  const double worstCaching = cach.size() > 1 ? *std::max_element(cach.begin() + 1, cach.end()) : 0;
  double meanSsim = 0;
  for (const double v : ssims) meanSsim += v / double(ssims.size());
  std::printf(
      "first_frame_ms=%.3f max_caching_after_first_ms=%.3f p95_over_median=%.3f "
      "blocks_behind=%lld mean_ssim=%.4f min_ssim=%.4f\n",
      lat.empty() ? 0.0 : lat[0], worstCaching,
      median(lat) > 0 ? percentile(lat, 0.95) / median(lat) : 0.0, (long long)behind,
      ssims.empty() ? -1.0 : meanSsim,
      ssims.empty() ? -1.0 : *std::min_element(ssims.begin(), ssims.end()));
  rusage self{};
  ::getrusage(RUSAGE_SELF, &self);
  std::printf("cache_peak_bytes=%llu frame_pool_peak_bytes=%llu peak_rss_kb=%ld\n",
              (unsigned long long)cachePeak, (unsigned long long)poolPeak, self.ru_maxrss);
  std::fflush(stdout);
  return 0;
}
