// SPDX-License-Identifier: BSD-3-Clause
#include "step_records.hpp"

#include <algorithm>
#include <cstring>
#include <type_traits>

#include "afam/base/errors.hpp"
#include "fitted_blocks.hpp"

namespace afam {

namespace {

/// The fixed part of a step's header; the scalar's name (nameBytes) follows it.
struct HeaderRecord {
  Index3 dims;
  std::array<double, 3> origin, spacing;
  double valueMin, valueMax, errorBound;
  int32_t levels, blocksPerAxis, degree, fixedNcp, sourceBytesPerSample;
  uint8_t relativeBound, mode, sampling;
  uint64_t nameBytes;
};
static_assert(std::is_trivially_copyable<HeaderRecord>::value, "records are copied as bytes");

}  // namespace

void StepRecorder::begin(const VolumeHeader& h) {
  HeaderRecord r{};
  r.dims = h.dims;
  r.origin = h.origin;
  r.spacing = h.spacing;
  r.valueMin = h.valueMin;
  r.valueMax = h.valueMax;
  r.errorBound = h.errorBound;
  r.levels = h.levels;
  r.blocksPerAxis = h.blocksPerAxis;
  r.degree = h.degree;
  r.fixedNcp = h.fixedNcp;
  r.sourceBytesPerSample = h.sourceBytesPerSample;
  r.relativeBound = h.relativeBound ? 1 : 0;
  r.mode = static_cast<uint8_t>(h.mode);
  r.sampling = static_cast<uint8_t>(h.sampling);
  r.nameBytes = h.scalarName.size();
  bytes_.resize(sizeof r + h.scalarName.size());
  std::memcpy(bytes_.data(), &r, sizeof r);
  std::copy(h.scalarName.begin(), h.scalarName.end(), bytes_.begin() + sizeof r);
  next_.begin(h);
}

void StepRecorder::add(const ModelEntry& entry, const void* stored) {
  BlockTask t;
  t.ijk = entry.block;
  t.entry = entry;
  const auto* p = static_cast<const uint8_t*>(stored);
  t.stored.assign(p, p + entry.storedSize);
  appendFittedBlock(t, bytes_);
  next_.add(entry, stored);
}

void replayStep(const std::vector<uint8_t>& bytes, ModelSink& sink) {
  HeaderRecord r{};
  if (bytes.size() < sizeof r) throw FormatError("a run's step: its header is cut short");
  std::memcpy(&r, bytes.data(), sizeof r);
  if (bytes.size() - sizeof r < r.nameBytes)
    throw FormatError("a run's step: its scalar name is cut short");
  VolumeHeader h;
  h.dims = r.dims;
  h.origin = r.origin;
  h.spacing = r.spacing;
  h.valueMin = r.valueMin;
  h.valueMax = r.valueMax;
  h.errorBound = r.errorBound;
  h.levels = r.levels;
  h.blocksPerAxis = r.blocksPerAxis;
  h.degree = r.degree;
  h.fixedNcp = r.fixedNcp;
  h.sourceBytesPerSample = r.sourceBytesPerSample;
  h.relativeBound = r.relativeBound != 0;
  h.mode = static_cast<EncodingMode>(r.mode);
  h.sampling = static_cast<LevelSampling>(r.sampling);
  const auto name = bytes.begin() + std::ptrdiff_t(sizeof r);
  h.scalarName.assign(name, name + std::ptrdiff_t(r.nameBytes));
  std::vector<BlockTask> tasks;
  readFittedBlocks(std::vector<uint8_t>(name + std::ptrdiff_t(r.nameBytes), bytes.end()), tasks);
  sink.begin(h);
  for (const BlockTask& t : tasks) sink.add(t.entry, t.stored.data());
}

}  // namespace afam
