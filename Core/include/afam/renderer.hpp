// SPDX-License-Identifier: BSD-3-Clause
// The out-of-core multi-resolution renderer of one .afam file (the paper's Algorithms 2-4).
//
// One frame:  prepare()  = LOD cut -> frustum and TF culling -> cache lookups (misses read from the
//                          file) -> FrameView + float pool of the visible models     ("caching")
//             then castRays (CPU here; the CUDA path and the VTK mapper take the PreparedFrame)
//                          while the prefetch thread loads the predicted next view   ("rendering")
//             latency = caching + rendering.
// The "build the FrameView for a frame" step (prepare) is separate from "cast rays on the CPU"
// (renderFrame), so the GPU path and the VTK mapper reuse it unchanged: a PreparedFrame owns every
// array its FrameView points to (host memory); a GPU path copies them and re-points the view.
// The method follows the file: Adaptive-FAM / FAM files give spline slots, DS files raw slots.
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "afam/afam_file.hpp"
#include "afam/cache.hpp"
#include "afam/camera.hpp"
#include "afam/image.hpp"
#include "afam/lod.hpp"
#include "afam/prefetch.hpp"
#include "afam/raycast.hpp"
#include "afam/transfer_function.hpp"

namespace afam {

struct RenderOptions {
  int threads = 0;                ///< ray-casting threads (0 = all cores)
  float sampleDistance = 0.005f;  ///< normalised units ([-1, 1]^3 volume)
  bool shading = true;
  LodOptions lod;
  CacheBudget cache{0, 200};      ///< the paper's 200 micro-models by default
  bool cold = false;              ///< drop the file from the OS page cache before each frame
  double storageMBps = 0;         ///< emulated storage bandwidth cap in MB/s (1e6 B/s); 0 = none
  std::string prefetch = "none";  ///< none | linear
  int tfTableSize = 1024;
  bool hasTransferFunction = false;  ///< false: TransferFunction::preset over the file's range
  TransferFunction transferFunction;
  float ambient = 0.3f, diffuse = 0.6f, specular = 0.3f, specularPower = 20.f;
  /// BlendMode (raycast.hpp): composite (0) or maximum / minimum / average intensity projection
  /// (average: VTK's opaque grey level of the opacity-weighted mean value). Projections use the
  /// table's own opacity, not corrected for the sample distance. No projection culls blocks by the transfer function (a block the table makes
  /// transparent can still hold a ray's largest or smallest value, and counts in the mean).
  int blendMode = 0;
};

struct FrameStats {
  double cachingMs = 0, renderMs = 0, latencyMs = 0;
  uint64_t hits = 0, misses = 0, bytesRead = 0;      ///< frame lookups and all reads during the frame
  uint64_t prefetchedBlocks = 0, prefetchedBytes = 0;  ///< loaded by the prefetch thread during the frame
  CullCounts culled;
  int64_t slots = 0;                                 ///< models in the FrameView
  uint64_t poolBytes = 0;
  /// The cache's resident bytes at the end of the frame, and the most it held during the frame
  /// (frame and prefetch loads); both stay within the cache's byte budget.
  uint64_t cacheBytes = 0, cachePeakBytes = 0;
};

/// Everything a FrameView points to, owned. Do not copy it after bind(); move is fine only if
/// bind() is called again.
struct PreparedFrame {
  FrameView view;
  std::vector<FrameSlot> slots;
  std::vector<float> pool;
  std::vector<int32_t> cellSlot;
  std::array<std::vector<float>, 3> cellBounds;
  std::vector<float> tf;
  std::vector<int64_t> entries;  ///< file entries of the slots, slot order
  void bind();                   ///< points view at the vectors above
};

class Renderer {
 public:
  Renderer(std::shared_ptr<const AfamFile> file, RenderOptions options);
  ~Renderer();

  const AfamFile& file() const { return *file_; }
  const RenderOptions& options() const { return options_; }
  LruCache& cache() { return *cache_; }
  const std::vector<float>& tfTable() const { return tf_; }
  double tfLo() const { return tfLo_; }
  double tfHi() const { return tfHi_; }

  /// LOD cut + culling for a camera (no I/O).
  Selection select(const Camera& camera) const;
  /// A FrameView with camera, geometry, TF and shading set, and no models (cellSlot all -1).
  void prepareEmpty(const Camera& camera, PreparedFrame& frame) const;
  /// The caching step: selection, cache loads, FrameView + pool. Fills stats' caching fields.
  void prepare(const Camera& camera, PreparedFrame& frame, FrameStats& stats);
  /// One full frame on the CPU: [drop OS cache if cold] prepare, start prefetch of the predicted
  /// next view, cast rays, stop prefetch. Appends the camera to the prediction history.
  /// maxDistance (optional, caller-owned, width * height floats, row 0 = top): per-pixel ray
  /// length limit from opaque geometry (FrameView::maxDistance); the installed caster sees it too.
  ImageRGBA renderFrame(const Camera& camera, FrameStats& stats,
                        const float* maxDistance = nullptr);

  /// Replaces renderFrame's CPU ray casting (the CUDA path of `--device gpu` plugs in here): the
  /// caster fills `image` (premultiplied RGBA of frame.view's size) from the prepared frame.
  using RayCaster = std::function<void(const PreparedFrame& frame, ImageRGBA& image)>;
  void setRayCaster(RayCaster caster) { caster_ = std::move(caster); }

 private:
  std::shared_ptr<const AfamFile> file_;
  RenderOptions options_;
  LodSelector lod_;
  std::unique_ptr<LruCache> cache_;
  std::unique_ptr<Predictor> predictor_;
  std::unique_ptr<Prefetcher> prefetcher_;
  std::vector<Camera> history_;
  std::vector<float> tf_;
  double tfLo_ = 0, tfHi_ = 1;
  std::array<std::vector<float>, 3> bounds_;
  RayCaster caster_;  ///< empty: renderCpu
};

}  // namespace afam
