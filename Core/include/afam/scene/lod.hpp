// SPDX-License-Identifier: BSD-3-Clause
// Level-of-detail selection as a cut of the block octree, and the culling of the cut.
//
// The cut is built top-down from level 0 (coarsest): a block is replaced by its children while the
// policy asks for a finer level at that block; so every finest cell is covered by exactly one
// block of the cut (no overlap, no hole) for any policy.
//  * Distance policy (the paper): the distance d from the point of view to the block's centroid,
//    both in the normalised frame ([-1, 1]^3), picks a band [0, 0.8), [0.8, 1.6), [1.6, 2.4),
//    [2.4, inf) (band width configurable); band b asks for level L-1-b (band 0 -> finest, clamped
//    at level 0).
//  * Screen policy: refine while the block's sample spacing (stride * voxel size, normalised
//    frame) projected at the distance of the block's nearest point exceeds pixelBudget pixels;
//    a block containing the eye is always refined.
// Culling, applied to the cut in this order, each rule counting the blocks and bytes it removed:
//  * frustum: the block's box lies entirely outside one side plane of the view frustum, or
//    entirely behind the near plane (such a block is not refined: the cut's blocks outside the
//    frustum are counted at the coarsest level that lies outside, not at the policy's level);
//  * transfer function: the maximum table opacity over the entry's [min, max] widened by a margin
//    (max(entry maxError, 1% of the value range), because the stored min/max are the model's
//    values at the samples and a spline may overshoot slightly between them) is zero. The
//    min/max of a masked entry (some samples missing) are over its valid samples, so a masked
//    block is culled as its valid range says, unless missing samples are drawn (the transfer
//    function's NaN opacity > 0: drawMissing);
//  * empty: a block with no valid sample (BlockKind::Empty) has nothing to draw unless missing
//    samples are drawn, whatever the blend mode and the tfCulling option (its cells stay -1, so
//    empty-space skipping sees it and it costs no sampling).
#pragma once

#include <cstdint>
#include <vector>

#include "afam/format/afam_file.hpp"
#include "afam/format/partition.hpp"
#include "afam/scene/camera.hpp"

namespace afam {

enum class LodPolicy { Distance, Screen };

struct LodOptions {
  LodPolicy policy = LodPolicy::Distance;
  double bandWidth = 0.8;    ///< distance policy: band edges at k * bandWidth
  double pixelBudget = 1.0;  ///< screen policy: allowed projected sample spacing in pixels
  bool frustumCulling = true;
  bool tfCulling = true;
  int forceLevel = -1;  ///< >= 0: every block at this level (benchmarks, tests); -1 = policy
};

/// One block of a cut: level and ijk; entry is the file's entry index (-1 without a file).
struct BlockRef {
  int level = 0;
  Int3 ijk{};
  int64_t entry = -1;
};

struct CullCounts {
  int64_t cutBlocks = 0, cutBytes = 0;          ///< the whole LOD cut
  int64_t frustumBlocks = 0, frustumBytes = 0;  ///< removed by frustum culling
  int64_t tfBlocks = 0, tfBytes = 0;            ///< removed by transfer-function culling
  int64_t emptyBlocks = 0;  ///< empty blocks (no valid sample, no bytes) removed: nothing to draw
  int64_t visibleBlocks = 0, visibleBytes = 0;  ///< left to load and render
  /// Removed because their region lies outside a rank's box (RendererResources::box; counted
  /// after the other culling): another rank draws them.
  int64_t otherRankBlocks = 0, otherRankBytes = 0;
};

struct Selection {
  std::vector<BlockRef> visible;
  CullCounts counts;
};

/// Normalised-frame box of a block ([-1, 1]^3 volume; voxel x maps to -1 + 2 x / (N-1)).
void blockBox(const Partition& p, int level, Int3 ijk, double lo[3], double hi[3]);

/// The view frustum's five planes (sides and near), computed once for many boxes.
struct FrustumPlanes {
  explicit FrustumPlanes(const Camera& camera);
  /// True when the box lies entirely outside one of the planes.
  bool outside(const double lo[3], const double hi[3]) const;
  Vec3 n[5], q[5];  ///< inward normals and points on the planes
};

class LodSelector {
 public:
  explicit LodSelector(LodOptions options = {}) : options_(options) {}
  const LodOptions& options() const { return options_; }

  /// The LOD cut for a camera (no culling). Covers every finest cell exactly once.
  std::vector<BlockRef> cut(const Partition& p, const Camera& camera) const;

  /// True when the block's box is entirely outside the camera's frustum.
  static bool outsideFrustum(const Camera& camera, const double lo[3], const double hi[3]);

  /// The cut, except that a block outside `prune` (when given) is not refined: it is culled, and
  /// so would all of its children be.
  std::vector<BlockRef> cut(const Partition& p, const Camera& camera,
                            const FrustumPlanes* prune) const;

  /// Cut + frustum culling + TF culling + empty blocks against a file's index (no payload is
  /// read). tfTable spans [tfLo, tfHi]; an empty table disables TF culling. drawMissing: missing
  /// samples are drawn (NaN opacity > 0), so empty and masked blocks stay.
  Selection select(const AfamFile& file, const Camera& camera, const std::vector<float>& tfTable,
                   double tfLo, double tfHi, bool drawMissing = false) const;

 private:
  int desiredLevel(const Partition& p, int level, Int3 ijk, const Camera& camera) const;
  LodOptions options_;
};

}  // namespace afam
