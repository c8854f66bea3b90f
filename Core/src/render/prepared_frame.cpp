// SPDX-License-Identifier: BSD-3-Clause
#include "afam/render/prepared_frame.hpp"

#include <algorithm>
#include <cstring>
#include <limits>
#include <string>

#include "afam/base/errors.hpp"
#include "afam/base/thread_scratch.hpp"

namespace afam {

void PreparedFrame::bind() {
  view.slots = slots.data();
  view.slotCount = int32_t(slots.size());
  view.pool = pool.empty() ? nullptr : pool.data();
  view.cellSlot = cellSlot.data();
  for (int a = 0; a < 3; ++a) view.cellBounds[a] = cellBounds[a].data();
  view.tf = tf.data();
  view.tfSize = int32_t(tf.size() / 4);
}

std::string writeModel(const ModelEntry& e, const CachedModel& m, float* out, uint64_t floats) {
  if (!m.isStored()) {
    if (!m.empty()) std::memcpy(out, m.data(), m.size() * sizeof(float));
    return {};
  }
  try {
    decodeStoredPayload(e, m.stored.data(), out, Partition::blockName(e.level, e.block));
  } catch (const FormatError& error) {
    std::fill(out, out + floats, std::numeric_limits<float>::quiet_NaN());
    return error.what();
  }
  return {};
}

uint64_t PreparedFrame::slotFloats(size_t s) const {
  return models[s]->isStored() ? slotFloatCount(slots[s]) : models[s]->size();
}

std::string PreparedFrame::writeSlot(size_t s, float* out) const {
  return writeModel(*slotEntries[s], *models[s], out, slotFloats(s));
}

const float* PreparedFrame::hostPool(std::vector<float>& storage) const {
  if (view.pool || slots.empty()) return view.pool;
  uint64_t floats = 0;
  for (size_t s = 0; s < slots.size(); ++s)
    floats = std::max(floats, slots[s].offset + slotFloats(s));
  storage.resize(floats);
  // A stored model that does not decode is NaN (drawn as nothing); the caster that asked for the
  // stored form reports it.
  for (size_t s = 0; s < slots.size(); ++s) writeSlot(s, storage.data() + slots[s].offset);
  releaseThreadScratch();  // of the stored models decoded here
  return storage.data();
}

FrameView PreparedFrame::hostView(std::vector<float>& storage) const {
  FrameView v = view;
  const bool floats =
      std::none_of(models.begin(), models.end(), [](const Payload& m) { return m->isStored(); });
  if (!v.pool && floats && slotHost.size() == slots.size())
    v.slotData = slotHost.data();
  else
    v.pool = hostPool(storage);
  return v;
}

FrameSlot modelSlot(const AfamFile& file, const BlockRef& model, uint64_t offset) {
  const Partition& p = file.partition();
  const bool raw = file.header().mode == EncodingMode::Downsampled;
  const ModelEntry& e = file.entries()[size_t(model.entry)];
  FrameSlot s;
  s.kind = raw ? kSlotRaw : kSlotSpline;
  s.level = model.level;
  const BlockExtent ext = p.extent(model.level, model.ijk);
  for (int a = 0; a < 3; ++a) {
    if (raw) {
      s.knots[a] = Knots{};
      s.knots[a].ncp = e.ncp[a];
      s.knots[a].degree = 1;
    } else {
      s.knots[a] = Knots::make(e.ncp[a], e.degree[a]);
    }
    s.lo[a] = float(ext.lo[a]);
    s.invExtent[a] = ext.hi[a] > ext.lo[a] ? float(1.0 / double(ext.hi[a] - ext.lo[a])) : 0.f;
  }
  s.offset = offset;
  // The values the source had there: its samples' range within the file's (raycast.hpp clamps).
  const VolumeHeader& h = file.header();
  s.valueMin = float(std::max(double(e.minValue), h.valueMin));
  s.valueMax = float(std::min(double(e.maxValue), h.valueMax));
  if (!(s.valueMin <= s.valueMax)) s.valueMin = s.valueMax = float(h.valueMin);
  if (e.kind == BlockKind::Empty) s.kind = kSlotEmpty;
  if (e.masked) {
    for (int a = 0; a < 3; ++a) s.maskSamples[a] = e.samples[a];
    s.maskOffset = uint32_t(controlCount(e));
  }
  return s;
}

void setCompactForm(const CompactForm& form, FrameSlot& slot) {
  slot.codeWidth = form.width;
  slot.codeTable = form.width ? form.table : 0;
}

namespace {

/// The normalised-frame coordinate of voxel coordinate x on axis a (toVoxel's inverse).
float normalisedOf(const FrameView& v, int a, float x) {
  return v.voxelPerUnit[a] > 0.f ? v.boxLo[a] + x / v.voxelPerUnit[a] : v.boxLo[a];
}

void cullOutside(PreparedFrame& frame, const CellBox& box) {
  const int* n = frame.view.gridDims;
  size_t i = 0;
  for (int z = 0; z < n[2]; ++z)
    for (int y = 0; y < n[1]; ++y)
      for (int x = 0; x < n[0]; ++x, ++i)
        if (!box.contains({x, y, z})) frame.cellSlot[i] = -1;
}

}  // namespace

void clipFrameToBox(PreparedFrame& frame, const CellBox& box) {
  FrameView& v = frame.view;
  for (int a = 0; a < 3; ++a)
    if (!box.empty() && (box.lo[a] < 0 || box.hi[a] > v.gridDims[a]))
      throw InvalidArgument("box frame: the box's cells " + std::to_string(box.lo[a]) + ".." +
                            std::to_string(box.hi[a]) + " on axis " + std::to_string(a) +
                            " lie outside the frame's " + std::to_string(v.gridDims[a]));
  cullOutside(frame, box);
  v.clipped = 1;
  for (int a = 0; a < 3; ++a) {
    const std::vector<float>& bounds = frame.cellBounds[size_t(a)];
    const int lo = box.empty() ? 0 : box.lo[a], hi = box.empty() ? 0 : box.hi[a];
    v.clipLo[a] = normalisedOf(v, a, bounds[size_t(lo)]);
    v.clipHi[a] = box.empty() ? v.clipLo[a] : normalisedOf(v, a, bounds[size_t(hi)]);
    if (v.voxelPerUnit[a] <= 0.f) v.clipHi[a] = v.boxHi[a];  // a one-sample axis: all of it
  }
  frame.bind();
}

}  // namespace afam
