// SPDX-License-Identifier: BSD-3-Clause
// The per-ray logic of every Adaptive-FAM ray caster, written ONCE for the host and the device.
//
// This header is the contract between the CPU ray caster (Core/src/cpu_raycaster.cpp), the CUDA
// kernel (CudaKernels/) and the analytic ground truth (ground_truth.hpp). All three call
// castRay<Shaded>() / castRayWith<Shaded>() with the same FrameView; they differ only in where the
// pointers of the FrameView live (host or device memory) and, for the ground truth, in the sampler.
//
// Rules for this file: no std:: containers, no exceptions, no virtual functions, no allocation;
// every struct is trivially copyable so that a FrameView is passed to a kernel by value; pointers
// are raw and device-agnostic (the CUDA launcher fills them with device pointers).
//
// ---------------------------------------------------------------------------------------------
// Coordinate systems
// ---------------------------------------------------------------------------------------------
//  * Normalised frame: the paper's frame, in which the volume's bounding box is [boxLo, boxHi]
//    (normally [-1, 1]^3, every axis rescaled independently as in the paper). Cameras, rays,
//    sample distance, LOD distances and shading all live in this frame.
//  * Voxel frame: continuous voxel index coordinates x in [0, dims-1] per axis, the frame of
//    Partition's block extents. x = (n - boxLo) * voxelPerUnit, voxelPerUnit =
//    (dims-1)/(boxHi-boxLo) (0 on a one-sample axis).
//  * Model parameters: a micro-model covering voxel extent [lo, hi] on an axis is evaluated at
//    u = (x - lo) / (hi - lo), clamped to [0, 1] (u = 0 when hi == lo).
//
// ---------------------------------------------------------------------------------------------
// Per-frame model lookup in O(1)
// ---------------------------------------------------------------------------------------------
//  The finest block grid (gridDims = finest blocks per axis, Bf) is the indirection grid. For each
//  finest cell, cellSlot[(cz * By + cy) * Bx + cx] holds the slot of the micro-model that covers it
//  in this frame's LOD cut (a coarse block fills all its finest cells with its slot), or -1 when
//  the cell is culled (outside the frustum, transparent under the TF, or absent). The cell of a
//  voxel coordinate x is floor(x * cellPerVoxel) corrected by at most one step against the finest
//  boundaries cellBounds[a][0..Bf] (voxel coordinates, Partition's rounding), so lookup cost does
//  not depend on how many blocks are visible. A point on a shared boundary belongs to the upper
//  cell (x >= bounds[c+1] -> c+1), except at the last boundary of the volume.
//
// ---------------------------------------------------------------------------------------------
// Slots and the float pool
// ---------------------------------------------------------------------------------------------
//  slots[s] describes one resident model; its floats start at pool + slots[s].offset, or, where
//  the frame references the cached models themselves (a CPU frame: slotData set, no pool), at
//  slotData[s] (slotModel()).
//  * kSlotSpline: B-spline micro-model (Adaptive-FAM and FAM). knots[a] = Knots::make(ncp, degree);
//    control points ncp.x*ncp.y*ncp.z, x fastest (the .afam payload unchanged).
//  * kSlotRaw: downsampled raw block (DS). knots[a].ncp = samples+2 (one ghost sample per side,
//    clamped at the volume edge), knots[a].degree unused; samples k = 0..n-1 sit at
//    lo + k (hi-lo)/(n-1), ghost k = -1 and k = n one sample spacing outside. Trilinear
//    interpolation, gradient by central differences of one sample spacing.
//  * kSlotEmpty: a block with no valid sample (BlockKind::Empty; no floats). Every sample in it is
//    missing. The Renderer makes such slots only when missing samples are drawn (nanOpacity > 0);
//    otherwise an empty block's cells are -1 like a culled block's, so it costs no sampling.
//  * A masked slot (maskSamples[0] > 0: a model some of whose samples are missing) keeps the
//    mask words of block_mask.hpp at pool + offset + maskOffset (right after the control points,
//    as the cache holds them). A sample position is missing when the NEAREST sample of the
//    block's maskSamples grid (its Partition samples: k at lo + k (hi-lo)/(n-1)) is missing, so a
//    decode on the sample grid gives NaN exactly at the missing samples.
//
// ---------------------------------------------------------------------------------------------
// Missing samples
// ---------------------------------------------------------------------------------------------
//  A sampler reports a missing sample as value NaN (missingValue(); a culled cell is `false`, as
//  before). castRayWith: by default (nanOpacity 0) a missing sample contributes nothing: no
//  colour, no opacity, and no gradient is taken there (the valid samples' gradients are the
//  spline's, which the encoder extrapolates smoothly into the holes, so no halo appears at the
//  mask's boundary). With nanOpacity > 0 a missing sample is drawn, unshaded, in nanColor with
//  nanOpacity (per tfReferenceDistance, corrected for the sample distance like the table's alpha).
//  Projections (castProjectionRayWith) take the valid samples only; a ray whose every sample is
//  missing gets nanColor at nanOpacity (0 by default: nothing).
//
// ---------------------------------------------------------------------------------------------
// Ray extent and sample positions (pixels and rays: scene/ray_camera.hpp)
// ---------------------------------------------------------------------------------------------
//  Rays start at max(box entry, nearDistance): a camera inside the volume starts at its near plane.
//  They end at min(box exit, maxDistance[pixel]) when the frame carries the per-pixel distances of
//  opaque geometry (depth compositing with a scene; no sample lies behind an opaque surface).
//  Samples are taken at t = tEnter + (k + j) * dt (k integer, tEnter where the ray enters the
//  volume's box, j in [0, 1) the pixel's jitter when FrameView::jitter is on, else 0): the
//  lattice starts on the box, like VTK's, so its samples do not lie on spheres around the eye
//  (which cut a volume's iso-surfaces into rings), and the jitter turns the remaining banding into
//  fine noise that is the same in every frame. All samplers see the same positions. In
//  compositing, sample k stands for [t_k, t_k + dt], the first one from the ray's start and the
//  last one up to its end (endWeight), so the opacity varies continuously where the near plane or
//  opaque geometry cut the lattice (no grid on the faces).
//  A frame that draws one rank's box (FrameView::clipped) marches the same rays on the same
//  lattice with the same end weights, but only near its box, and its cells outside the box are
//  culled: each sample is drawn by exactly one box, so the boxes' images composited in
//  visibility order are the whole frame's image.
//
// ---------------------------------------------------------------------------------------------
// Classification, shading, compositing
// ---------------------------------------------------------------------------------------------
//  tf: tfSize RGBA entries (float, interleaved r,g,b,a) spanning [tfMin, tfMax], linearly
//  interpolated, clamped outside. The alpha of an entry is the opacity of a segment of length
//  tfReferenceDistance; a sample uses alpha' = 1 - (1 - alpha)^(sampleDistance /
//  tfReferenceDistance). Shading (Shaded = true): Phong with a headlight (light at the eye, L = V =
//  -d), two-sided normals n = normalize(gradient in the normalised frame):
//      c_out = c * (ambient + diffuse * |n.L|) + specular * |n.H|^specularPower * specularColor
//  (H = L for a headlight). Where |gradient| < 1e-12 the sample is unshaded (c_out = c).
//  With Shaded = false no gradient is ever computed (the evaluation is compiled with
//  WithGradient = false); with Shaded = true it is computed only for samples whose classified
//  opacity is non-zero (value first, then value + gradient).
//  A table whose alpha is already corrected for the sample distance is signalled by
//  tfReferenceDistance == sampleDistance: no pow() per sample then (the Renderer does this).
//  Compositing is front to back with premultiplied colour; the ray stops once the accumulated
//  opacity reaches terminationOpacity (kTerminationOpacity). castRay returns premultiplied RGBA;
//  compose it over a background with c + (1 - a) * background.
#pragma once

#include <stdint.h>

#include "afam/base/host_device.hpp"
#include "afam/format/block_mask.hpp"
#include "afam/format/compact_form.hpp"
#include "afam/scene/ray_camera.hpp"
#include "afam/spline/basis.hpp"
#include "afam/spline/evaluate.hpp"

#if !defined(__CUDACC__)
#include <cmath>
#include <cstring>
#endif

namespace afam {

/// The opacity at which a composited ray stops by default (early ray termination): VTK's
/// 1 - 1/255, so that the light a ray leaves out is below one step of an 8-bit channel, and the
/// ranks of a sort-last frame, each stopping on its own in its box, composite the image of one
/// renderer within 1/255 (ranks/rank_images.hpp). 0.95 left up to 12.75/255 out; the samples
/// after it cost 2-12% more ray casting (bench_render's BM_TerminationOpacity).
constexpr float kTerminationOpacity = 1.f - 1.f / 255.f;

/// Premultiplied colour and opacity of one ray.
struct RGBA {
  float r = 0.f, g = 0.f, b = 0.f, a = 0.f;
};

enum SlotKind : int32_t { kSlotSpline = 0, kSlotRaw = 1, kSlotEmpty = 2 };

/// One resident model of this frame. Trivially copyable.
struct FrameSlot {
  int32_t kind = kSlotSpline;  ///< SlotKind
  int32_t level = 0;           ///< LOD level of the model (diagnostics only)
  Knots knots[3];              ///< spline: implied knots; raw: knots[a].ncp = padded sample count
  float lo[3] = {0.f, 0.f, 0.f};         ///< block extent, voxel coordinates
  float invExtent[3] = {0.f, 0.f, 0.f};  ///< 1 / (hi - lo), 0 on a one-sample axis
  uint64_t offset = 0;                   ///< first float of this model in FrameView::pool
  /// Masked slots: samples per axis of the block's grid the mask covers; {0, 0, 0}: no mask.
  int32_t maskSamples[3] = {0, 0, 0};
  /// Masked slots: floats from `offset` to the first mask word (the control points before them),
  /// so the mask moves with the model when a GPU pool places it elsewhere.
  uint32_t maskOffset = 0;
  /// A spline model kept as codes (CachedModel's compact form): codeWidth bytes a control point
  /// (1 or 2; 0: float32 points), its table of codeTable floats first, the codes right after
  /// them (packed, the last float padded).
  int32_t codeWidth = 0;
  uint32_t codeTable = 0;
  /// The values the source had over this block (its samples' min and max, within the file's
  /// range): every value sampled from the slot is clamped to [valueMin, valueMax], so a spline's
  /// overshoot at a sharp edge is never classified as a value the data never had. The defaults
  /// clamp nothing.
  float valueMin = -3.0e38f, valueMax = 3.0e38f;
};

/// Floats of a slot's model in the pool: control points (or raw samples) and mask words.
AFAM_HD uint64_t slotFloatCount(const FrameSlot& s) {
  if (s.kind == kSlotEmpty) return 0;
  uint64_t control = uint64_t(s.knots[0].ncp) * s.knots[1].ncp * s.knots[2].ncp;
  if (s.codeWidth > 0) control = compactFloats(s.codeTable, uint64_t(s.codeWidth), control);
  if (s.maskSamples[0] <= 0) return control;
  return control +
         uint64_t(maskWordCount(int64_t(s.maskSamples[0]) * s.maskSamples[1] * s.maskSamples[2]));
}

/// Everything a ray needs for one frame. Trivially copyable; all pointers are non-owning and
/// point into host memory (CPU caster) or device memory (CUDA kernel).
struct FrameView {
  RayCamera camera;

  // Volume placement.
  float boxLo[3] = {-1.f, -1.f, -1.f};  ///< volume bounding box, normalised frame
  float boxHi[3] = {1.f, 1.f, 1.f};
  float voxelPerUnit[3] = {0.f, 0.f, 0.f};  ///< (dims-1) / (boxHi-boxLo); 0 on a one-sample axis
  float voxelMax[3] = {0.f, 0.f, 0.f};      ///< dims-1

  // Indirection grid over the finest block grid.
  int gridDims[3] = {1, 1, 1};              ///< finest blocks per axis (Bf)
  float cellPerVoxel[3] = {0.f, 0.f, 0.f};  ///< Bf / (dims-1) (estimate before the +-1 correction)
  const float* cellBounds[3] = {nullptr, nullptr,
                                nullptr};  ///< Bf+1 finest boundaries per axis, voxel coords
  const int32_t* cellSlot = nullptr;       ///< Bx*By*Bz, x fastest: slot index or -1

  // Resident models.
  const FrameSlot* slots = nullptr;
  int32_t slotCount = 0;
  const float* pool = nullptr;  ///< control points / raw samples of all slots
  /// Host frames only: slot s's floats at slotData[s] (the cached model itself, its offset
  /// unused); null: at pool + offset (a device frame's pool, or a copy).
  const float* const* slotData = nullptr;

  // Transfer function.
  const float* tf = nullptr;  ///< tfSize RGBA entries, interleaved
  int32_t tfSize = 0;
  float tfMin = 0.f, tfMax = 1.f;
  float tfReferenceDistance = 0.01f;  ///< segment length the table's alpha refers to
  /// Missing samples: drawn (unshaded) in nanColor with opacity nanOpacity (per
  /// tfReferenceDistance, like the table's alpha) when nanOpacity > 0; nothing by default.
  float nanColor[3] = {0.5f, 0.f, 0.f};
  float nanOpacity = 0.f;

  // Sampling and shading.
  float sampleDistance = 0.01f;                    ///< normalised units
  float terminationOpacity = kTerminationOpacity;  ///< FrameSettings::terminationOpacity
  float ambient = 0.3f, diffuse = 0.6f, specular = 0.3f, specularPower = 20.f;
  float specularColor[3] = {1.f, 1.f, 1.f};
  int32_t shading = 1;  ///< informative: the caster picks castRay<true> or castRay<false> from it
  /// BlendMode: composite (0, castRayWith) or a projection (castProjectionRayWith). The casters
  /// (CPU and CUDA) pick the function from it.
  int32_t blendMode = 0;
  /// Shaded rays: 1 evaluates value and gradient together at every sample (one model evaluation
  /// per sample; best when most samples are visible), 0 evaluates the value first and the gradient
  /// again only where the transfer function gives opacity (best for sparse transfer functions).
  int32_t gradientWithValue = 1;

  // Opaque geometry (optional): per pixel, the largest ray distance t from the ray's origin (the
  // eye; parallel projection: the pixel's point on the eye plane; normalised
  // units, camera.width * camera.height floats, row 0 = top) at which samples are still taken;
  // a ray stops where an opaque surface is. nullptr (default): no limit, no cost.
  const float* maxDistance = nullptr;
  /// 1: each pixel's samples are shifted along its ray by a fraction of a step that depends on
  /// the pixel only (rayJitter; VTK's UseJittering), which turns the banding of a regular lattice
  /// into fine noise and is stable from frame to frame; 0: none.
  int32_t jitter = 0;
  /// 1: the frame draws one rank's box of the volume (sort-last rendering; clipFrameToBox):
  /// each ray takes only the samples of the volume's ray (the same lattice, the same end weights)
  /// near [clipLo, clipHi] (normalised frame), and the cells outside the box hold -1, so a sample
  /// is drawn by the one box whose finest cell holds it. 0: the whole volume.
  int32_t clipped = 0;
  float clipLo[3] = {-1.f, -1.f, -1.f};
  float clipHi[3] = {1.f, 1.f, 1.f};
};

// ---------------------------------------------------------------------------------------------
// Small math helpers
// ---------------------------------------------------------------------------------------------
namespace rc {

AFAM_HD float minf(float a, float b) { return a < b ? a : b; }
AFAM_HD float maxf(float a, float b) { return a > b ? a : b; }
AFAM_HD float clampf(float x, float a, float b) { return x < a ? a : (x > b ? b : x); }
AFAM_HD float dot3(const float* a, const float* b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

}  // namespace rc

/// Slab test of the ray o + t d against [lo, hi]; returns false when it misses.
AFAM_HD bool intersectBox(const float* o, const float* d, const float* lo, const float* hi,
                          float& tEnter, float& tExit) {
  float t0 = -3.0e38f, t1 = 3.0e38f;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.f) {
      if (o[a] < lo[a] || o[a] > hi[a]) return false;
      continue;
    }
    const float inv = 1.f / d[a];
    float ta = (lo[a] - o[a]) * inv, tb = (hi[a] - o[a]) * inv;
    if (ta > tb) {
      const float s = ta;
      ta = tb;
      tb = s;
    }
    t0 = rc::maxf(t0, ta);
    t1 = rc::minf(t1, tb);
  }
  tEnter = t0;
  tExit = t1;
  return t1 >= t0;
}

// ---------------------------------------------------------------------------------------------
// Lookup: normalised point -> voxel coordinate -> finest cell -> slot
// ---------------------------------------------------------------------------------------------

/// Voxel coordinates of a normalised-frame point, clamped to the volume.
AFAM_HD void toVoxel(const FrameView& f, const float* p, float* x) {
  for (int a = 0; a < 3; ++a)
    x[a] = rc::clampf((p[a] - f.boxLo[a]) * f.voxelPerUnit[a], 0.f, f.voxelMax[a]);
}

/// Finest cell on one axis in O(1): floor estimate, then one +-1 correction against the bounds.
AFAM_HD int findCell(const FrameView& f, int axis, float x) {
  const int n = f.gridDims[axis];
  int c = int(x * f.cellPerVoxel[axis]);
  c = c < 0 ? 0 : (c > n - 1 ? n - 1 : c);
  const float* b = f.cellBounds[axis];
  if (c > 0 && x < b[c])
    --c;
  else if (c < n - 1 && x >= b[c + 1])
    ++c;
  return c;
}

/// Slot covering voxel coordinate x, or -1 (culled / empty).
AFAM_HD int32_t lookupSlot(const FrameView& f, const float* x) {
  const int cx = findCell(f, 0, x[0]);
  const int cy = findCell(f, 1, x[1]);
  const int cz = findCell(f, 2, x[2]);
  return f.cellSlot[(int64_t(cz) * f.gridDims[1] + cy) * f.gridDims[0] + cx];
}

// ---------------------------------------------------------------------------------------------
// Model evaluation
// ---------------------------------------------------------------------------------------------

/// Spline slot: value (and gradient in voxel units, d/dx) at voxel coordinate x. ReadsCodes false:
/// the slot holds float32 points (evaluateModel's promise).
template <bool WithGradient, bool ReadsCodes = true>
AFAM_HD float sampleSplineSlot(const FrameSlot& s, const float* data, const float* x,
                               float* gVoxel) {
  ModelView m;
  m.knots[0] = s.knots[0];
  m.knots[1] = s.knots[1];
  m.knots[2] = s.knots[2];
  m.control = data;
  if (s.codeWidth > 0) {
    m.codes = data + s.codeTable;
    m.codeWidth = s.codeWidth;
  }
  const float u = (x[0] - s.lo[0]) * s.invExtent[0];
  const float v = (x[1] - s.lo[1]) * s.invExtent[1];
  const float w = (x[2] - s.lo[2]) * s.invExtent[2];
  float g[3];
  const float value =
      evaluateModel<WithGradient, ReadsCodes>(m, u, v, w, WithGradient ? g : nullptr);
  if (WithGradient) {
    gVoxel[0] = g[0] * s.invExtent[0];
    gVoxel[1] = g[1] * s.invExtent[1];
    gVoxel[2] = g[2] * s.invExtent[2];
  }
  return value;
}

/// Trilinear interpolation of a padded raw block at padded sample coordinates t (clamped).
AFAM_HD float trilinearRaw(const FrameSlot& s, const float* data, float tx, float ty, float tz) {
  const int nx = s.knots[0].ncp, ny = s.knots[1].ncp, nz = s.knots[2].ncp;
  const float t[3] = {rc::clampf(tx, 0.f, float(nx - 1)), rc::clampf(ty, 0.f, float(ny - 1)),
                      rc::clampf(tz, 0.f, float(nz - 1))};
  const int n[3] = {nx, ny, nz};
  int i0[3];
  float fr[3];
  for (int a = 0; a < 3; ++a) {
    int i = int(t[a]);
    i = i > n[a] - 2 ? n[a] - 2 : i;
    i = i < 0 ? 0 : i;
    i0[a] = i;
    fr[a] = n[a] > 1 ? t[a] - float(i) : 0.f;
  }
  const int sx = nx > 1 ? 1 : 0;
  const int sy = ny > 1 ? nx : 0;
  const int sz = nz > 1 ? nx * ny : 0;
  const float* c = data + (int64_t(i0[2]) * ny + i0[1]) * nx + i0[0];
  const float c00 = c[0] + fr[0] * (c[sx] - c[0]);
  const float c10 = c[sy] + fr[0] * (c[sy + sx] - c[sy]);
  const float c01 = c[sz] + fr[0] * (c[sz + sx] - c[sz]);
  const float c11 = c[sz + sy] + fr[0] * (c[sz + sy + sx] - c[sz + sy]);
  const float c0 = c00 + fr[1] * (c10 - c00);
  const float c1 = c01 + fr[1] * (c11 - c01);
  return c0 + fr[2] * (c1 - c0);
}

/// Raw (DS) slot: trilinear value and central-difference gradient in voxel units.
template <bool WithGradient>
AFAM_HD float sampleRawSlot(const FrameSlot& s, const float* data, const float* x, float* gVoxel) {
  float t[3], perVoxel[3];
  for (int a = 0; a < 3; ++a) {
    const int n = s.knots[a].ncp - 2;  // real samples on this axis
    const float samplesPerVoxel = float(n - 1) * s.invExtent[a];
    perVoxel[a] = samplesPerVoxel;
    t[a] = (x[a] - s.lo[a]) * samplesPerVoxel + 1.f;
  }
  const float value = trilinearRaw(s, data, t[0], t[1], t[2]);
  if (WithGradient) {
    gVoxel[0] = 0.5f *
                (trilinearRaw(s, data, t[0] + 1.f, t[1], t[2]) -
                 trilinearRaw(s, data, t[0] - 1.f, t[1], t[2])) *
                perVoxel[0];
    gVoxel[1] = 0.5f *
                (trilinearRaw(s, data, t[0], t[1] + 1.f, t[2]) -
                 trilinearRaw(s, data, t[0], t[1] - 1.f, t[2])) *
                perVoxel[1];
    gVoxel[2] = 0.5f *
                (trilinearRaw(s, data, t[0], t[1], t[2] + 1.f) -
                 trilinearRaw(s, data, t[0], t[1], t[2] - 1.f)) *
                perVoxel[2];
  }
  return value;
}

/// The value a sampler reports for a missing sample: a quiet NaN.
AFAM_HD float missingValue() {
  const uint32_t bits = 0x7fc00000u;
#if defined(__CUDA_ARCH__)
  return __uint_as_float(bits);
#else
  float v;
  std::memcpy(&v, &bits, sizeof v);
  return v;
#endif
}

/// Whether a sampled value stands for a missing sample (NaN).
AFAM_HD bool isMissing(float value) { return value != value; }

/// Whether voxel coordinate x of slot s is valid: its nearest sample of the mask's grid is (an
/// unmasked slot: always; an empty slot: never).
AFAM_HD bool slotSampleValid(const FrameSlot& s, const float* data, const float* x) {
  if (s.kind == kSlotEmpty) return false;
  if (s.maskSamples[0] <= 0) return true;
  int64_t index = 0;
  for (int a = 2; a >= 0; --a) {
    const int n = s.maskSamples[a];
    const float u = rc::clampf((x[a] - s.lo[a]) * s.invExtent[a], 0.f, 1.f);
    int k = int(u * float(n - 1) + 0.5f);
    k = k > n - 1 ? n - 1 : k;
    index = index * n + k;
  }
  return maskBit(data + s.maskOffset, index);
}

/// Value (and gradient in voxel units) of slot s at voxel coordinate x, missingValue() (gradient
/// 0) where the slot's sample there is missing, clamped to the slot's value range: every model
/// sampler's evaluation.
template <bool WithGradient, int FixedDegree = -1, bool ReadsCodes = true>
AFAM_HD float sampleSlot(const FrameSlot& stored, const float* data, const float* x,
                         float* gVoxel) {
  if (!slotSampleValid(stored, data, x)) {
    if (WithGradient) gVoxel[0] = gVoxel[1] = gVoxel[2] = 0.f;
    return missingValue();
  }
  float value;
  if (stored.kind == kSlotRaw) {
    value = sampleRawSlot<WithGradient>(stored, data, x, gVoxel);
  } else if (FixedDegree > 0) {
    FrameSlot s = stored;
    s.knots[0].degree = FixedDegree;
    s.knots[1].degree = FixedDegree;
    s.knots[2].degree = FixedDegree;
    value = sampleSplineSlot<WithGradient, ReadsCodes>(s, data, x, gVoxel);
  } else {
    value = sampleSplineSlot<WithGradient, ReadsCodes>(stored, data, x, gVoxel);
  }
  return rc::clampf(value, stored.valueMin, stored.valueMax);  // NaN stays NaN
}

/// The first float of slot s's model.
AFAM_HD const float* slotModel(const FrameView& f, int32_t s) {
  return f.slotData ? f.slotData[s] : f.pool + f.slots[s].offset;
}

/// Voxel coordinate x of a normalised-frame point p and the slot covering it (-1: culled / empty):
/// the first step of every model sampler.
AFAM_HD int32_t locateSample(const FrameView& f, const float* p, float* x) {
  toVoxel(f, p, x);
  return lookupSlot(f, x);
}

/// A gradient in voxel units (d/dx) to the normalised frame.
AFAM_HD void voxelToNormalisedGradient(const FrameView& f, const float* gVoxel, float* gradient) {
  gradient[0] = gVoxel[0] * f.voxelPerUnit[0];
  gradient[1] = gVoxel[1] * f.voxelPerUnit[1];
  gradient[2] = gVoxel[2] * f.voxelPerUnit[2];
}

/// The default sampler: the frame's resident micro-models (spline or raw), found in O(1).
/// A sampler provides `template <bool G> bool sample(const FrameView&, const float* p, float&
/// value, float* gradient) const` with p and gradient in the NORMALISED frame; it returns false
/// where nothing is to be sampled (culled cell), and value NaN (missingValue()) at a missing
/// sample. castRayWith<> accepts any such sampler
/// (ground_truth.hpp plugs the analytic Marschner-Lobb function in here). FixedDegree > 0 promises
/// that every spline slot of the frame has that degree on all axes: the slot's knots are copied
/// with the degree as a compile-time constant, so the compiler unrolls the basis and tensor loops
/// of evaluateModel and keeps their arrays in registers (the CUDA kernels specialise this way; the
/// values are those of the generic path, same functions, same operations). ReadsCodes false
/// promises that no slot holds its model as codes (FrameSlot::codeWidth 0).
template <int FixedDegree = -1, bool ReadsCodes = true>
struct ModelSamplerT {
  template <bool WithGradient>
  AFAM_HD bool sample(const FrameView& f, const float* p, float& value, float* gradient) const {
    float x[3];
    const int32_t slot = locateSample(f, p, x);
    if (slot < 0) return false;
    float gv[3] = {0.f, 0.f, 0.f};
    value =
        sampleSlot<WithGradient, FixedDegree, ReadsCodes>(f.slots[slot], slotModel(f, slot), x, gv);
    if (WithGradient) voxelToNormalisedGradient(f, gv, gradient);
    return true;
  }
};
using ModelSampler = ModelSamplerT<>;

/// Wraps a sampler and counts the ray samples that hit a model (benchmarks: samples per second).
/// castRayWith evaluates each sample once (value, or value + gradient with gradientWithValue), and
/// with gradientWithValue = 0 value + gradient again for visible samples when shaded: only the
/// first evaluation of each sample is counted.
template <typename Inner>
struct SampleCounter {
  Inner inner;
  unsigned* count;
  template <bool WithGradient>
  AFAM_HD bool sample(const FrameView& f, const float* p, float& value, float* gradient) const {
    const bool ok = inner.template sample<WithGradient>(f, p, value, gradient);
    if (ok && (!WithGradient || f.gradientWithValue != 0)) ++*count;
    return ok;
  }
};

// ---------------------------------------------------------------------------------------------
// Classification, shading, compositing
// ---------------------------------------------------------------------------------------------

/// Transfer-function lookup (linear between entries): colour and alpha per tfReferenceDistance.
AFAM_HD RGBA classify(const FrameView& f, float value) {
  RGBA out;
  if (f.tfSize <= 0) return out;
  const float range = f.tfMax - f.tfMin;
  float t = range > 0.f ? (value - f.tfMin) / range : 0.f;
  t = rc::clampf(t, 0.f, 1.f) * float(f.tfSize - 1);
  if (!(t >= 0.f)) t = 0.f;  // NaN
  int i = int(t);
  if (i > f.tfSize - 2) i = f.tfSize - 2;
  if (i < 0) i = 0;
  const float w = f.tfSize > 1 ? t - float(i) : 0.f;
  const float* e0 = f.tf + 4 * i;
  const float* e1 = f.tfSize > 1 ? e0 + 4 : e0;
  out.r = e0[0] + w * (e1[0] - e0[0]);
  out.g = e0[1] + w * (e1[1] - e0[1]);
  out.b = e0[2] + w * (e1[2] - e0[2]);
  out.a = e0[3] + w * (e1[3] - e0[3]);
  return out;
}

/// Opacity correction for the sample distance: 1 - (1 - alpha)^(sampleDistance / reference).
AFAM_HD float correctOpacity(float alpha, float ratio) {
  alpha = rc::clampf(alpha, 0.f, 1.f);
  if (alpha >= 1.f) return 1.f;
  return 1.f - powf(1.f - alpha, ratio);
}

/// Phong with a headlight; `d` is the unit ray direction, `g` the gradient (normalised frame).
AFAM_HD void shadePhong(const FrameView& f, const float* d, const float* g, RGBA& c) {
  const float len2 = rc::dot3(g, g);
  if (!(len2 > 1e-24f)) return;  // flat or NaN: unshaded
  const float inv = 1.f / sqrtf(len2);
  float ndl = -(g[0] * d[0] + g[1] * d[1] + g[2] * d[2]) * inv;  // n.L with L = -d
  ndl = ndl < 0.f ? -ndl : ndl;                                  // two-sided
  // Integral exponents (the usual case, 20 by default) by binary powering: a handful of
  // multiplications instead of powf, the same operations on the host and the device.
  const float e = f.specularPower;
  const int ie = int(e);
  float sp;
  if (float(ie) == e && ie >= 0 && ie <= 1024) {
    sp = 1.f;
    float base = ndl;
    for (int n = ie; n > 0; n >>= 1) {
      if (n & 1) sp *= base;
      base *= base;
    }
  } else {
    sp = powf(ndl, e);
  }
  const float spec = f.specular * sp;
  const float k = f.ambient + f.diffuse * ndl;
  c.r = c.r * k + spec * f.specularColor[0];
  c.g = c.g * k + spec * f.specularColor[1];
  c.b = c.b * k + spec * f.specularColor[2];
}

/// A missing sample drawn with the frame's NaN colour and opacity (per tfReferenceDistance).
AFAM_HD RGBA missingColour(const FrameView& f) {
  RGBA c;
  c.r = f.nanColor[0];
  c.g = f.nanColor[1];
  c.b = f.nanColor[2];
  c.a = f.nanOpacity;
  return c;
}

/// `behind` (premultiplied) composited under `acc` (premultiplied): front-to-back "over", how the
/// images of boxes in visibility order become one (ranks/rank_images.hpp).
AFAM_HD void compositeUnder(RGBA& acc, const RGBA& behind) {
  const float w = 1.f - acc.a;
  acc.r += w * behind.r;
  acc.g += w * behind.g;
  acc.b += w * behind.b;
  acc.a += w * behind.a;
}

/// Front-to-back compositing of one classified (non-premultiplied) sample into `acc`.
AFAM_HD void compositeFrontToBack(RGBA& acc, const RGBA& s) {
  const float w = (1.f - acc.a) * s.a;
  acc.r += w * s.r;
  acc.g += w * s.g;
  acc.b += w * s.b;
  acc.a += w;
}

// ---------------------------------------------------------------------------------------------
// The ray
// ---------------------------------------------------------------------------------------------

/// The fraction of a step, in [0, 1), by which pixel (px, py)'s samples are shifted along its ray
/// when FrameView::jitter is on: an integer hash of the pixel (the same every frame, uncorrelated
/// between neighbours).
AFAM_HD float rayJitter(int px, int py) {
  uint32_t h = uint32_t(px) * 0x8da6b343u ^ uint32_t(py) * 0xd8163841u;
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  h ^= h >> 16;
  return float(h >> 8) * (1.f / 16777216.f);
}

/// The samples of pixel (px, py): origin o, unit direction d, step dt and the indices
/// [kBegin, kEnd] of the samples t = tBase + k dt (sampleAt) this frame takes. The lattice starts
/// where the ray enters the volume's box (plus the pixel's jitter), so the samples lie on the box's
/// faces and not on spheres around the eye (which draw rings through a volume); N ranks that draw
/// parts of one box see the same lattice: a clipped frame (FrameView::clipped) takes the samples of
/// [kFirst, kLast] within a step of its box. False when the ray takes none: it misses the box (or
/// the clip box), opaque geometry or the near plane cuts it off, or sampleDistance <= 0.
struct RaySamples {
  float o[3], d[3];
  float dt;
  float tBase;  ///< t of sample 0
  int64_t kBegin, kEnd;
  int64_t kFirst, kLast;  ///< the first and last samples of the volume's whole ray
  float tStart, tExit;    ///< the part of the ray sampled (box, near plane, opaque geometry)
};
/// A clipped frame's samples: those of the whole ray within one step of the clip box (which
/// sample a box draws is decided by the cell holding it, not by this test). False: none.
AFAM_HD bool clipRaySamples(const FrameView& f, RaySamples& r) {
  float c0, c1;
  if (!intersectBox(r.o, r.d, f.clipLo, f.clipHi, c0, c1)) return false;
  const int64_t first = int64_t(ceilf((c0 - r.tBase) / r.dt)) - 1;
  const int64_t last = int64_t(floorf((c1 - r.tBase) / r.dt)) + 1;
  r.kBegin = first > r.kFirst ? first : r.kFirst;
  r.kEnd = last < r.kLast ? last : r.kLast;
  return r.kBegin <= r.kEnd;
}

AFAM_HD bool raySamples(const FrameView& f, int px, int py, RaySamples& r) {
  pixelRay(f.camera, px, py, r.o, r.d);
  float tEnter, tExit;
  if (!intersectBox(r.o, r.d, f.boxLo, f.boxHi, tEnter, tExit)) return false;
  if (f.maxDistance) tExit = rc::minf(tExit, f.maxDistance[int64_t(py) * f.camera.width + px]);
  const float tStart = rc::maxf(tEnter, f.camera.nearDistance);
  if (tExit < tStart || !(f.sampleDistance > 0.f)) return false;
  // The opacity correction refers to sampleDistance: rayStep keeps the world length of a step.
  r.dt = rayStep(f.camera, r.d, f.sampleDistance);
  r.tBase = tEnter + (f.jitter ? rayJitter(px, py) : 0.f) * r.dt;
  r.kBegin = r.kFirst = int64_t(ceilf((tStart - r.tBase) / r.dt));
  r.kEnd = r.kLast = int64_t(floorf((tExit - r.tBase) / r.dt));
  r.tStart = tStart;
  r.tExit = tExit;
  return !f.clipped || clipRaySamples(f, r);
}

/// Ray distance t of sample k.
AFAM_HD float sampleAt(const RaySamples& r, int64_t k) { return r.tBase + float(k) * r.dt; }

/// The length of ray sample k stands for, in steps: sample k stands for [t_k, t_k + dt], the
/// first from the ray's start (1 to 2 steps), the last up to its end (0 to 1 step), a lone one for
/// the whole ray. The opacity a ray gathers then changes continuously as the box entry, the exit
/// or opaque geometry crosses the lattice (whole samples switching on and off there draw a grid
/// on the volume's faces), and a ray cut short by geometry gathers no more than the whole ray.
AFAM_HD float endWeight(const RaySamples& r, int64_t k) {
  if (k != r.kFirst && k != r.kLast) return 1.f;
  const float lo = k == r.kFirst ? r.tStart : sampleAt(r, k);
  const float hi = k == r.kLast ? r.tExit : sampleAt(r, k) + r.dt;
  return rc::maxf(0.f, hi - lo) / r.dt;
}

/// March pixel (px, py) through the volume with any sampler; returns premultiplied RGBA.
template <bool Shaded, typename Sampler>
AFAM_HD RGBA castRayWith(const FrameView& f, const Sampler& sampler, int px, int py) {
  RGBA acc;
  RaySamples r;
  if (!raySamples(f, px, py, r)) return acc;
  const float* d = r.d;
  const float ratio =
      f.sampleDistance / (f.tfReferenceDistance > 0.f ? f.tfReferenceDistance : f.sampleDistance);
  for (int64_t k = r.kBegin; k <= r.kEnd; ++k) {
    const float t = sampleAt(r, k);
    const float weight = endWeight(r, k);
    const float p[3] = {r.o[0] + t * d[0], r.o[1] + t * d[1], r.o[2] + t * d[2]};
    float value = 0.f;
    float g[3] = {0.f, 0.f, 0.f};
    // Shaded and gradientWithValue: one evaluation of value and gradient per sample. Otherwise the
    // value first, and the gradient only for samples the transfer function makes visible.
    const bool together = Shaded && f.gradientWithValue != 0;
    if (together) {
      if (!sampler.template sample<true>(f, p, value, g)) continue;
    } else if (!sampler.template sample<false>(f, p, value, g)) {
      continue;
    }
    RGBA c;
    if (isMissing(value)) {  // drawn in the NaN colour or not at all; never shaded
      if (!(f.nanOpacity > 0.f)) continue;
      c = missingColour(f);
    } else {
      c = classify(f, value);
      if (c.a <= 0.f) continue;
      if (Shaded) {
        if (!together) sampler.template sample<true>(f, p, value, g);
        shadePhong(f, d, g, c);
      }
    }
    if (ratio * weight != 1.f) c.a = correctOpacity(c.a, ratio * weight);
    compositeFrontToBack(acc, c);
    if (acc.a >= f.terminationOpacity) break;
  }
  return acc;
}

/// out = c with its colour premultiplied by its opacity.
AFAM_HD void premultiply(const RGBA& c, RGBA& out) {
  out.r = c.r * c.a;
  out.g = c.g * c.a;
  out.b = c.b * c.a;
  out.a = c.a;
}

/// Blend modes, numbered as VTK's vtkVolumeMapper::BlendModes.
enum BlendMode : int32_t {
  kBlendComposite = 0,  ///< front-to-back compositing (castRayWith)
  kBlendMaximum = 1,    ///< maximum intensity projection
  kBlendMinimum = 2,    ///< minimum intensity projection
  kBlendAverage = 3     ///< mean of the ray's samples
};

/// Projection ray (FrameView::blendMode 1-3): the same rays and sample lattice as castRayWith,
/// values only (no gradient, no early termination). Maximum / minimum: the ray's largest /
/// smallest value is classified once by the table, whose alpha is the opacity of the projection
/// (not corrected for the sample distance). Average, as VTK's vtkGPUVolumeRayCastMapper: an
/// opaque grey level, the mean over the ray's samples of opacity (the table's own, as for
/// maximum and minimum) times the value mapped over [tfMin, tfMax], clamped to [0, 1]. Returns
/// premultiplied RGBA; nothing when the ray takes no sample.
template <typename Sampler>
AFAM_HD RGBA castProjectionRayWith(const FrameView& f, const Sampler& sampler, int px, int py) {
  RGBA acc;
  RaySamples r;
  if (!raySamples(f, px, py, r)) return acc;
  float best = 0.f, sum = 0.f;
  int64_t n = 0;
  bool missed = false;  // the ray met a missing sample
  for (int64_t k = r.kBegin; k <= r.kEnd; ++k) {
    const float t = sampleAt(r, k);
    const float p[3] = {r.o[0] + t * r.d[0], r.o[1] + t * r.d[1], r.o[2] + t * r.d[2]};
    float value = 0.f, g[3] = {0.f, 0.f, 0.f};
    if (!sampler.template sample<false>(f, p, value, g)) continue;
    if (isMissing(value)) {
      missed = true;
      continue;
    }
    if (n == 0)
      best = value;
    else
      best = f.blendMode == kBlendMinimum ? rc::minf(best, value) : rc::maxf(best, value);
    if (f.blendMode == kBlendAverage) sum += classify(f, value).a * (value - f.tfMin);
    ++n;
  }
  if (n == 0) {
    if (missed && f.nanOpacity > 0.f) premultiply(missingColour(f), acc);
    return acc;
  }
  if (f.blendMode == kBlendAverage) {
    const float span = f.tfMax - f.tfMin;
    const float grey = span > 0.f ? rc::clampf(sum / (float(n) * span), 0.f, 1.f) : 0.f;
    acc.r = acc.g = acc.b = grey;
    acc.a = 1.f;
    return acc;
  }
  premultiply(classify(f, best), acc);
  return acc;
}

/// The ray of the resident micro-models: what the CPU caster and the CUDA kernel call per pixel.
template <bool Shaded>
AFAM_HD RGBA castRay(const FrameView& f, int px, int py) {
  return castRayWith<Shaded>(f, ModelSampler{}, px, py);
}

}  // namespace afam
