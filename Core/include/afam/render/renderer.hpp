// SPDX-License-Identifier: BSD-3-Clause
// The out-of-core multi-resolution renderer of one .afam file (the paper's Algorithms 2-4).
//
// A Renderer is built from what owns memory and threads (RendererResources: the RAM cache, the
// load threads, the prefetch thread, ray-casting threads; and its FrameCaster, setCaster); what a
// person edits while looking (FrameSettings: transfer function, shading, blend mode, sample
// distance, LOD, miss budget) goes with each frame, so an edit keeps the cache, the prefetcher's
// history and a GPU caster's model pool. Where a frame's image goes and what stops its rays
// (FrameTargets) go with each frame too.
//
// One frame:  prepare()  = LOD cut -> frustum and TF culling -> cache lookups; the misses read
//                          and decoded by the load threads at once (BlockLoader), waited for up
//                          to the miss budget, a coarser resident model standing in for a block
//                          still loading -> FrameView over the visible models       ("caching")
//             then the FrameCaster (the CPU's, or the CUDA path's GpuCaster) casts it into the
//                          frame's targets while the load threads fetch the predicted next
//                          view's blocks                                            ("rendering")
//             latency = caching + rendering.
// What prepare() hands a caster (PreparedFrame) is the frame contract of prepared_frame.hpp.
// The method follows the file: Adaptive-FAM / FAM files give spline slots, DS files raw slots.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "afam/format/afam_file.hpp"
#include "afam/predict/predictor.hpp"
#include "afam/render/block_loader.hpp"
#include "afam/render/cache.hpp"
#include "afam/render/damage.hpp"
#include "afam/render/frame_budget.hpp"
#include "afam/render/frame_caster.hpp"
#include "afam/render/frame_settings.hpp"
#include "afam/render/image.hpp"
#include "afam/render/prefetch.hpp"
#include "afam/render/prepared_frame.hpp"
#include "afam/render/raycast.hpp"
#include "afam/render/tail_reserve.hpp"
#include "afam/scene/camera.hpp"
#include "afam/scene/lod.hpp"
#include "afam/scene/transfer_function.hpp"

namespace afam {

/// What a Renderer owns for its whole life: memory (the RAM cache), threads (ray casting, the
/// prefetch thread and its predictor) and the way the file is read. Changing any of these needs a
/// new Renderer.
struct RendererResources {
  int threads = 0;      ///< ray-casting threads (0 = all cores)
  int loadThreads = 0;  ///< threads that read and decode a frame's misses (0 = all cores)
  /// How much lower the load and prefetch threads' priority is than the frame's (nice steps,
  /// 0..19; 0: the same): a frame under a miss budget gets a core at its deadline even while
  /// they decode on every core.
  int loadNice = 3;
  CacheBudget cache{0, 200};      ///< the paper's 200 micro-models by default
  bool cold = false;              ///< drop the file from the OS page cache before each frame
  double storageMBps = 0;         ///< emulated storage bandwidth cap in MB/s (1e6 B/s); 0 = none
  std::string prefetch = "none";  ///< none | linear | appa | forecache | lstm
  /// Integer-coded models cached in their compact form (cache.hpp; false: float32 control
  /// points, for comparison). The same images either way.
  bool compactModels = true;
  /// One rank's share of the volume in sort-last rendering (its box of finest cells;
  /// ranks/rank_boxes.hpp splits a file among N ranks). The renderer then selects, loads, caches
  /// and prefetches only the blocks whose region meets the box (a coarser block spanning several
  /// boxes is read by each of their ranks) and draws only inside it (clipFrameToBox); the LOD cut
  /// and the culling are the whole volume's, the same on every rank, restricted to the box. Cells
  /// beyond the volume's grid are dropped: a box outside it, or an empty box, draws a transparent
  /// image and reads nothing. None (default): the whole volume.
  std::optional<CellBox> box;
};

/// Both at once, for front ends that set everything in one place (the command line, benchmarks).
struct RenderOptions : RendererResources, FrameSettings {};

struct FrameStats {
  double cachingMs = 0, renderMs = 0, latencyMs = 0;
  /// Of cachingMs: the LOD cut and its culling, and the wait for the frame's misses to load (the
  /// rest places the models: pins, lookups, slots).
  double selectMs = 0, waitMs = 0;
  uint64_t hits = 0, misses = 0, bytesRead = 0;  ///< frame lookups and all reads during the frame
  uint64_t prefetchedBlocks = 0,
           prefetchedBytes = 0;  ///< loaded by the prefetch thread during the frame
  CullCounts culled;
  /// Blocks of the selection still loading when the frame's miss budget ran out
  /// (FrameSettings::missBudgetMs), drawn from a resident coarser level; they are refined in the
  /// next frames. 0: the frame is exact.
  int64_t standInBlocks = 0;
  /// Blocks of the selection not drawn at their own level because the budget ran out: the
  /// stand-ins, and blocks with no resident intact ancestor (drawn as nothing; none once the
  /// resident levels are in); and their models' decoded bytes (float32). 0: the frame is exact.
  int64_t blocksBehind = 0;
  uint64_t bytesBehind = 0;
  /// Coarsest levels kept resident for frames under a budget (frame_budget.hpp; 0: none yet),
  /// and the milliseconds this frame waited for them to load (the first such frame only).
  int residentLevels = 0;
  double residentLoadMs = 0;
  /// Loads of the load threads that failed for another reason than damage (I/O, a file changed
  /// on disk), one message each, handed out once; such a block is read again by the frame that
  /// needs it, which then fails with the same error.
  std::vector<std::string> loadErrors;
  int64_t slots = 0;  ///< models in the FrameView
  /// Bytes of the frame's models (copied into a frame pool only for a caster that reads one;
  /// the CPU's reads the cached models, a GPU's its own pool).
  uint64_t poolBytes = 0;
  /// The cache's resident bytes at the end of the frame, and the most it held during the frame
  /// (frame and prefetch loads); both stay within the cache's byte budget.
  uint64_t cacheBytes = 0, cachePeakBytes = 0;
  /// Damaged micro-models (damage.hpp): blocks of this frame's selection that are damaged (drawn
  /// from a coarser or finer level), of which those whose region stayed empty; every block of the
  /// file known to be damaged so far; and the reports of blocks first found damaged during this
  /// frame (by its loads or its prefetching), one sentence each, each handed out once.
  int64_t damagedBlocks = 0, emptyDamagedBlocks = 0, knownDamagedBlocks = 0;
  std::vector<std::string> damageReports;
  /// What the caster did: GPU or CPU, image left on the device, pixels the device depth limited,
  /// models uploaded, the GPU's own times, and its messages (frame_caster.hpp).
  CastResult cast;
};

class Renderer {
 public:
  /// damage: the file's damage log from an earlier Renderer of the same file (null: a new one),
  /// so that a damaged block is reported and read once per file however often the resources change.
  Renderer(std::shared_ptr<const AfamFile> file, RendererResources resources,
           FrameSettings settings = {}, std::shared_ptr<DamageLog> damage = nullptr);
  Renderer(std::shared_ptr<const AfamFile> file, const RenderOptions& options)
      : Renderer(std::move(file), RendererResources(options), FrameSettings(options)) {}
  ~Renderer();

  const AfamFile& file() const { return *file_; }
  const RendererResources& resources() const { return resources_; }
  /// The settings of the next frame; settings().transferFunction is the table's function (the
  /// preset when none was given).
  const FrameSettings& settings() const { return settings_; }
  LruCache& cache() { return *cache_; }
  BlockLoader& loader() { return *loader_; }
  const std::vector<float>& tfTable() const { return tf_; }
  double tfLo() const { return tfLo_; }
  double tfHi() const { return tfHi_; }

  /// Settings for the frames from now on: the transfer-function table, LOD and culling follow at
  /// once; the cache, the prefetcher and the caster are kept. Throws InvalidArgument
  /// (and changes nothing) for a sample distance that is not > 0, an unknown blend mode or a
  /// transfer function with non-finite points (frame_settings.hpp checks these for front ends that
  /// warn and keep the last good value instead). Not while a frame renders.
  void setFrameSettings(const FrameSettings& settings);

  /// LOD cut + culling for a camera (no I/O).
  Selection select(const Camera& camera) const;
  /// A FrameView with camera, geometry, TF and shading set, and no models (cellSlot all -1).
  void prepareEmpty(const Camera& camera, PreparedFrame& frame) const;
  /// The caching step: selection, cache loads (a damaged model replaced as damage.hpp says),
  /// FrameView + pool. Fills stats' caching and damage fields. Throws FileChangedError when the
  /// file changed on disk since it was opened (checked first, and by every read): the renderer
  /// is then done, and a new one on the file opened again draws its new contents.
  void prepare(const Camera& camera, PreparedFrame& frame, FrameStats& stats) {
    prepare(camera, frame, stats, true);
  }
  /// The same; with hostPool false the frame references the cached models (models, slotHost)
  /// and its pool stays empty.
  void prepare(const Camera& camera, PreparedFrame& frame, FrameStats& stats, bool hostPool);
  /// One full frame: [drop OS cache if cold] prepare, start prefetch of the predicted next view,
  /// cast rays with the caster into `targets` (this frame's only), stop prefetch. Appends the
  /// camera to the prediction history; stats.cast says what the caster did. The image is on the
  /// host unless stats.cast.imageOnDevice (then it holds the size only).
  ImageRGBA renderFrame(const Camera& camera, FrameStats& stats, const FrameTargets& targets);
  /// maxDistance (optional, caller-owned, width * height floats, row 0 = top): per-pixel ray
  /// length limit from opaque geometry (FrameTargets::maxDistance); the image on the host.
  ImageRGBA renderFrame(const Camera& camera, FrameStats& stats,
                        const float* maxDistance = nullptr);
  /// setFrameSettings(settings), then renderFrame.
  ImageRGBA renderFrame(const Camera& camera, const FrameSettings& settings, FrameStats& stats,
                        const FrameTargets& targets);
  ImageRGBA renderFrame(const Camera& camera, const FrameSettings& settings, FrameStats& stats,
                        const float* maxDistance = nullptr);

  /// Draws another step of the same run (AfamFile::open(path, step)) from the next frame on,
  /// keeping the cache, the load threads, the prefetcher's history and the caster's model pool:
  /// the models the steps share are neither read nor decoded nor uploaded again (modelKey).
  /// InvalidArgument for a file that is not a step of this run. Not while a frame renders.
  void setStep(std::shared_ptr<const AfamFile> step);
  /// The step likely shown next (the next one in playback, or the one before when playing
  /// backwards; null: none): each frame queues its view's models of that step for the load
  /// threads, after everything the frame itself asks for.
  void setNextStep(std::shared_ptr<const AfamFile> next);
  /// Casts the frames from now on with `caster` (the CUDA path's makeGpuCaster plugs in here);
  /// nullptr: the CPU's (CpuCaster on resources().threads, the default). The renderer owns it: a
  /// GPU caster's model pool then holds this file's models only.
  void setCaster(std::unique_ptr<FrameCaster> caster);
  /// The caster frames are cast with (never null).
  FrameCaster& caster() { return *caster_; }
  const FrameCaster& caster() const { return *caster_; }

 private:
  // frame_loads.cpp: what a frame draws, exact or under its miss budget
  std::vector<Placement> loadModels(const Selection& sel, const Camera& camera, FrameStats& stats,
                                    std::chrono::steady_clock::time_point deadline);
  std::vector<Placement> placeModels(const Selection& sel, const std::vector<int64_t>& missing,
                                     bool budgeted, FrameStats& stats);
  void placeOne(const BlockRef& b, Payload data, std::vector<Placement>& placed, FrameStats& stats);
  /// Loads the resident levels once (and after setStep); returns the milliseconds waited.
  double keepResidentLevels(FrameStats& stats);
  BlockRef parentOf(const BlockRef& block) const;  ///< the block of the level above holding it
  int standInLevel(const BlockRef& block) const;   ///< nearest resident intact ancestor; -1: none
  bool placeStandIn(const BlockRef& block, std::vector<Placement>& placed);
  bool isEmptyBlock(const BlockRef& block) const;  ///< no valid sample: no payload to load
  /// The entries whose region meets the rank's box (all of them without a box).
  std::vector<int64_t> inBox(const std::vector<int64_t>& entries) const;
  int32_t addSlot(const BlockRef& model, PreparedFrame& frame, uint64_t offset) const;
  void fillCells(const BlockRef& region, int32_t slot, PreparedFrame& frame) const;

  std::shared_ptr<const AfamFile> file_, next_;  ///< the step drawn, the one likely next
  RendererResources resources_;
  FrameSettings settings_;
  LodSelector lod_;
  std::unique_ptr<LruCache> cache_;
  std::unique_ptr<BlockLoader> loader_;  ///< after cache_: stops before the cache goes
  std::unique_ptr<Predictor> predictor_;
  std::unique_ptr<Prefetcher> prefetcher_;
  std::vector<Camera> history_;
  std::vector<float> tf_;
  double tfLo_ = 0, tfHi_ = 1;
  std::array<std::vector<float>, 3> bounds_;
  std::optional<CellBox> box_;  ///< resources_.box within the volume's finest cells
  std::unique_ptr<FrameCaster> caster_;
  bool residentReady_ = false;  ///< the resident levels of file_ loaded and kept
  int residentLevels_ = 0;
  TailReserve tailReserve_;  ///< how much sooner than its budget a frame stops waiting
  std::chrono::steady_clock::time_point waitEnd_;  ///< the end of this frame's wait for loads
};

}  // namespace afam
