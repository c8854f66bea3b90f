// SPDX-License-Identifier: BSD-3-Clause
// The frame contract: what a caster receives for one frame (PreparedFrame), whoever made it. A
// Renderer fills one per frame (LOD cut, culling, cache); the CPU caster, a GPU's caster and a
// rank's box read it, and none of them needs the renderer with its cache, loader and predictors.
// A PreparedFrame holds the cached models it draws (no copy) and owns the other arrays its
// FrameView points to (host memory); the CPU caster reads the cached models, a GPU caster uploads
// those its pool does not hold. A model the cache keeps in the stored form is decoded on the host
// by writeSlot (a host caster's pool, a GPU caster's model its decoder does not take).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "afam/format/afam_file.hpp"
#include "afam/render/cached_model.hpp"
#include "afam/render/raycast.hpp"
#include "afam/scene/lod.hpp"

namespace afam {

/// Everything a FrameView points to, owned. Do not copy it after bind(); move is fine only if
/// bind() is called again.
struct PreparedFrame {
  FrameView view;
  std::vector<FrameSlot> slots;
  /// The slots' floats side by side at their offsets; empty when the caster reads the cached
  /// models themselves (FrameCaster::readsHostPool false: no per-frame copy of every model).
  std::vector<float> pool;
  std::vector<int32_t> cellSlot;
  std::array<std::vector<float>, 3> cellBounds;
  std::vector<float> tf;
  std::vector<int64_t> entries;  ///< file entries of the slots, slot order
  /// modelKey of the slots' models, slot order: a GPU caster's pool keeps models by them, so that
  /// the steps of a run share what they share.
  std::vector<uint64_t> keys;
  /// The cached models of the slots, slot order (kept alive for the frame), and their floats
  /// (null for a model in the stored form: CachedModel::stored holds its payload).
  std::vector<Payload> models;
  std::vector<const float*> slotHost;
  /// The slots' index entries (the file's, valid while the renderer is): what decodes a model
  /// held in the stored form.
  std::vector<const ModelEntry*> slotEntries;
  void bind();  ///< points view at the vectors above (view.pool null while pool is empty)
  /// view.pool, or, when the pool was left empty, the slots' floats copied into `storage` (models
  /// in the stored form decoded there; one that does not decode is NaN: drawn as nothing).
  const float* hostPool(std::vector<float>& storage) const;
  /// The view a host caster casts: reading each slot's cached model where the pool was left
  /// empty and every model has its floats (slotData = slotHost), else hostPool's floats.
  FrameView hostView(std::vector<float>& storage) const;
  /// Floats of slot s's model (its control points, and a masked model's mask words).
  uint64_t slotFloats(size_t s) const;
  /// Writes slot s's slotFloats(s) floats at out: copied, or decoded from the stored form (NaN
  /// where its payload does not decode). Returns why it did not decode; empty when it did.
  std::string writeSlot(size_t s, float* out) const;
};

/// Restricts `frame` (a bound frame of the whole volume) to one rank's box of finest cells
/// (sort-last rendering; ranks/rank_boxes.hpp gives the boxes): cells outside it culled, rays
/// clipped to it (FrameView::clipped), bound again. Every ray keeps the whole volume's sample
/// lattice and end weights and is marched only near the box, so each sample is drawn by the one
/// box whose cell holds it, and a coarser model spanning several boxes by each within its own.
/// Early ray termination and the skipping of culled cells work inside the box as in any frame.
/// An empty box leaves every cell culled (a transparent image). Throws InvalidArgument for a box
/// outside the frame's grid.
void clipFrameToBox(PreparedFrame& frame, const CellBox& box);

/// Writes a cached model's `floats` floats at `out`: copied, or decoded from its stored form (the
/// one host decoding of a frame's models; NaN, drawn as nothing, where its payload does not
/// decode). Returns why it did not decode; empty when it did.
std::string writeModel(const ModelEntry& entry, const CachedModel& model, float* out,
                       uint64_t floats);

/// The FrameSlot of one model of `file` (a spline, or a DS file's raw block; extent in voxel
/// coordinates), its floats at `offset` of the pool.
FrameSlot modelSlot(const AfamFile& file, const BlockRef& model, uint64_t offset);
/// A slot of a model cached in the compact form `form` (width 0: floats): its code width and
/// table.
void setCompactForm(const CompactForm& form, FrameSlot& slot);

}  // namespace afam
