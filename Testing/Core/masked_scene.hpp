// SPDX-License-Identifier: BSD-3-Clause
// A volume with missing samples as a frame of the ray casters (CPU tests and the GPU comparison),
// built by hand the way an encoder and the Renderer would: every block fitted with BlockFitter to
// a field whose holes are filled (smoothly, or with a constant for the naive comparison), its
// mask words after its control points, a block with no valid sample an empty slot or a culled
// cell.
//
// The field is f = 0.7 + 0.06 sin(2 pi y / 40) cos(2 pi z / 36) (voxel coordinates): smooth and
// independent of x, so rays at any x see the same values. Samples with x index >= kFirstMissingX
// are missing (a half-space: positions x >= kFirstMissingX - 0.5 are missing under the casters'
// nearest-sample rule). 49 x 45 x 41 samples, one level of 4 x 4 x 4 blocks: the blocks of x
// index 3 (x 36..48) have no valid sample, those of index 2 (x 24..36) are masked.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "afam/format/partition.hpp"
#include "afam/render/raycast.hpp"
#include "afam/scene/camera.hpp"
#include "afam/scene/transfer_function.hpp"
#include "afam/spline/fit.hpp"

namespace afam_test {

constexpr int kFirstMissingX = 31;

inline float maskedSceneField(double y, double z) {
  return 0.7f + 0.06f * float(std::sin(2 * M_PI * y / 40.0) * std::cos(2 * M_PI * z / 36.0));
}

/// The transfer function: the valid values (0.64-0.76) dim and faint; a bright white band at
/// 0.3-0.45 that valid values never reach but a spline falling from them to a fill value of 0
/// crosses (a halo, were a constant fill drawn); transparent below 0.15 and at 0.5-0.56.
inline afam::TransferFunction maskedSceneTransferFunction() {
  afam::TransferFunction tf;
  tf.colors = {{0.0, 1, 1, 1}, {0.5, 1, 1, 1}, {0.56, 0.3, 0.35, 0.5}, {1.0, 0.3, 0.35, 0.5}};
  tf.opacities = {{0.0, 0.0}, {0.15, 0.0}, {0.3, 0.9},  {0.45, 0.9},
                  {0.5, 0.0}, {0.56, 0.0}, {0.6, 0.05}, {1.0, 0.05}};
  tf.referenceDistance = 0.02;
  return tf;
}

struct MaskedSceneOptions {
  bool smoothFill = true;    ///< false: missing samples filled with 0 before fitting (naive)
  bool drawMissing = false;  ///< empty blocks become kSlotEmpty slots (else their cells are -1)
  float nanOpacity = 0.f;
  float nanColor[3] = {0.1f, 0.8f, 0.2f};
  float sampleDistance = 0.01f;
  bool shaded = true;
};

/// The frame of the masked scene and the host arrays its FrameView points into.
struct MaskedScene {
  afam::Partition partition{afam::Index3{49, 45, 41}, 1, 4};
  std::array<std::vector<float>, 3> bounds;
  std::vector<int32_t> cellSlot;
  std::vector<afam::FrameSlot> slots;
  std::vector<uint64_t> keys;
  std::vector<float> pool;
  std::vector<float> tf;
  afam::FrameView view;
  int emptyBlocks = 0, maskedBlocks = 0;
  MaskedScene() = default;
  MaskedScene(const MaskedScene&) = delete;
  MaskedScene& operator=(const MaskedScene&) = delete;
};

/// The block's samples (the field, missing ones filled as options say) and its mask words.
inline int maskedBlockSamples(const afam::Partition& p, const afam::BlockExtent& e,
                              const MaskedSceneOptions& o, std::vector<float>& samples,
                              std::vector<uint32_t>& words) {
  const afam::Int3 n = e.samples;
  const int64_t count = int64_t(n[0]) * n[1] * n[2];
  samples.assign(size_t(count), 0.f);
  words.assign(size_t(afam::maskWordCount(count)), 0u);
  int valid = 0;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        const int64_t at = (int64_t(k) * n[1] + j) * n[0] + i;
        const bool ok = p.samplePosition(e, 0, i) < kFirstMissingX;
        samples[size_t(at)] = ok || o.smoothFill ? maskedSceneField(p.samplePosition(e, 1, j),
                                                                    p.samplePosition(e, 2, k))
                                                 : 0.f;
        if (ok) words[size_t(at >> 5)] |= 1u << (at & 31);
        valid += ok ? 1 : 0;
      }
  return valid;
}

/// Appends block ijk's slot (and its floats) to the scene; returns the slot or -1 (culled).
inline int32_t addMaskedBlock(MaskedScene& s, afam::Int3 ijk, const MaskedSceneOptions& o,
                              afam::BlockFitter& fitter) {
  const afam::BlockExtent e = s.partition.extent(0, ijk);
  std::vector<float> samples;
  std::vector<uint32_t> words;
  const int valid = maskedBlockSamples(s.partition, e, o, samples, words);
  const int64_t count = int64_t(samples.size());
  if (valid == 0) s.emptyBlocks++;
  if (valid == 0 && !o.drawMissing) return -1;
  afam::FrameSlot slot;
  for (int a = 0; a < 3; ++a) {
    slot.lo[a] = float(e.lo[a]);
    slot.invExtent[a] = e.hi[a] > e.lo[a] ? float(1.0 / double(e.hi[a] - e.lo[a])) : 0.f;
  }
  slot.offset = s.pool.size();
  if (valid == 0) {
    slot.kind = afam::kSlotEmpty;
  } else {
    const afam::FitResult fit = fitter.fit(samples.data(), e.samples, e.samples, 2, false);
    for (int a = 0; a < 3; ++a) slot.knots[a] = afam::Knots::make(fit.ncp[a], fit.degree[a]);
    s.pool.insert(s.pool.end(), fit.control.begin(), fit.control.end());
    if (valid < count) {
      s.maskedBlocks++;
      for (int a = 0; a < 3; ++a) slot.maskSamples[a] = e.samples[a];
      slot.maskOffset = uint32_t(fit.control.size());
      const float* bits = reinterpret_cast<const float*>(words.data());
      s.pool.insert(s.pool.end(), bits, bits + words.size());
    }
  }
  s.slots.push_back(slot);
  s.keys.push_back(uint64_t(s.partition.linearIndex(0, ijk)) + 1);
  return int32_t(s.slots.size() - 1);
}

/// Builds the masked scene seen by `camera`.
inline void buildMaskedScene(const afam::Camera& camera, const MaskedSceneOptions& o,
                             MaskedScene& s) {
  const afam::Partition& p = s.partition;
  const afam::Int3 b = p.blocksPerAxis(0);
  afam::FrameView& v = s.view;
  v = afam::FrameView{};
  v.camera = camera.toRayCamera();
  for (int a = 0; a < 3; ++a) {
    s.bounds[a].clear();
    for (int i = 0; i < b[a]; ++i) {
      afam::Int3 ijk{0, 0, 0};
      ijk[a] = i;
      const afam::BlockExtent e = p.extent(0, ijk);
      if (i == 0) s.bounds[a].push_back(float(e.lo[a]));
      s.bounds[a].push_back(float(e.hi[a]));
    }
    const double n1 = double(p.dims()[a] - 1);
    v.voxelPerUnit[a] = float(n1 / 2.0);
    v.voxelMax[a] = float(n1);
    v.gridDims[a] = b[a];
    v.cellPerVoxel[a] = float(double(b[a]) / n1);
    v.cellBounds[a] = s.bounds[a].data();
  }
  afam::BlockFitter fitter;
  s.cellSlot.clear();
  for (int z = 0; z < b[2]; ++z)
    for (int y = 0; y < b[1]; ++y)
      for (int x = 0; x < b[0]; ++x) s.cellSlot.push_back(addMaskedBlock(s, {x, y, z}, o, fitter));
  s.tf = maskedSceneTransferFunction().table(256, 0.0, 1.0);
  v.cellSlot = s.cellSlot.data();
  v.slots = s.slots.data();
  v.slotCount = int32_t(s.slots.size());
  v.pool = s.pool.data();
  v.tf = s.tf.data();
  v.tfSize = 256;
  v.tfMin = 0.f;
  v.tfMax = 1.f;
  v.tfReferenceDistance = 0.02f;
  v.sampleDistance = o.sampleDistance;
  v.shading = o.shaded ? 1 : 0;
  v.nanOpacity = o.nanOpacity;
  for (int a = 0; a < 3; ++a) v.nanColor[a] = o.nanColor[a];
}

/// The camera of the masked-scene tests: perspective, nearly along -z, a little off axis.
inline afam::Camera maskedSceneCamera(int width = 160, int height = 128) {
  return afam::Camera::lookAt({0.15, 0.1, 3.2}, {0.0, 0.0, 0.0}, {0, 1, 0}, 40.0, width, height);
}

/// The voxel x range a pixel's ray covers inside the volume's box; false when it misses the box.
inline bool rayVoxelXRange(const afam::FrameView& f, int px, int py, float& xMin, float& xMax) {
  float o[3], d[3], t0, t1;
  afam::pixelRay(f.camera, px, py, o, d);
  if (!afam::intersectBox(o, d, f.boxLo, f.boxHi, t0, t1)) return false;
  const float x0 = (o[0] + t0 * d[0] - f.boxLo[0]) * f.voxelPerUnit[0];
  const float x1 = (o[0] + t1 * d[0] - f.boxLo[0]) * f.voxelPerUnit[0];
  xMin = std::min(x0, x1);
  xMax = std::max(x0, x1);
  return true;
}

/// Pixels whose rays take samples, all of them missing: the whole ray inside the box lies at voxel
/// x >= kFirstMissingX - 0.5 (positions whose nearest sample is missing), with a margin.
inline std::vector<size_t> missingOnlyPixels(const afam::FrameView& f) {
  std::vector<size_t> out;
  for (int y = 0; y < f.camera.height; ++y)
    for (int x = 0; x < f.camera.width; ++x) {
      float lo, hi;
      afam::RaySamples r;
      if (rayVoxelXRange(f, x, y, lo, hi) && lo > kFirstMissingX - 0.45f &&
          afam::raySamples(f, x, y, r) && r.kEnd >= r.kBegin)
        out.push_back(size_t(y) * f.camera.width + x);
    }
  return out;
}

/// Luminance of a premultiplied pixel over black.
inline float luminance(const float* rgba) {
  return 0.2126f * rgba[0] + 0.7152f * rgba[1] + 0.0722f * rgba[2];
}

}  // namespace afam_test
