// SPDX-License-Identifier: BSD-3-Clause
#include "afam/format/step_extract.hpp"

#include <algorithm>
#include <limits>
#include <memory>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/format/run_writer.hpp"
#include "file_layout.hpp"

namespace afam {

namespace {

/// Where an extracted step goes: a version-2 file, or a version-3 file of one step when the
/// header keeps what version 2 has no field for (a pointwise bound, missing samples).
class ExtractWriter {
 public:
  ExtractWriter(const std::string& out, const AfamFile& file) {
    const VolumeHeader& h = file.header();
    if (h.boundKind == BoundKind::Rmse && h.missing == MissingKind::None) {
      v2_ = std::make_unique<AfamWriter>(out, h);
      return;
    }
    v3_ = std::make_unique<RunWriter>(out, h, 1, absoluteBound(h));
    v3_->beginStep(file.stepTimes()[size_t(file.step())]);
  }
  void add(const ModelEntry& e, const float* control) {
    if (v2_) return v2_->add(e, control);
    ModelEntry stored = e;
    stored.storedSize = payloadBytes(e.ncp);
    v3_->addStored(stored, control);
  }
  void addStored(const ModelEntry& e, const void* bytes) {
    if (v2_) return v2_->addStored(e, bytes);
    v3_->addStored(e, bytes);
  }
  /// Commits; returns the file's bytes. `lo`, `hi`: the step's range (a version-3 step row).
  uint64_t commit(float lo, float hi) {
    if (v2_) {
      v2_->commit();
      return v2_->bytesWritten();
    }
    v3_->endStep(lo, hi);
    return v3_->commit();
  }

 private:
  std::unique_ptr<AfamWriter> v2_;
  std::unique_ptr<RunWriter> v3_;
};

}  // namespace

ExtractStats extractStep(const std::string& run, int64_t step, const std::string& out) {
  const std::shared_ptr<const AfamFile> file = AfamFile::open(run, step);
  ExtractWriter writer(out, *file);
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  ExtractStats stats;
  std::vector<uint8_t> stored;
  const std::vector<ModelEntry>& entries = file->entries();
  for (size_t i = 0; i < entries.size(); ++i) {
    ModelEntry e = entries[i];
    const std::string where =
        run + ": " + Partition::blockName(e.level, e.block) + " of step " + std::to_string(step);
    if (e.residual) {  // the chain's sum, as float32 control points of the same model
      const std::vector<float> control = file->readPayload(int64_t(i));
      e.residual = false;
      e.coded = false;
      e.integerCoded = e.lanesCoded = false;
      if (e.kind == BlockKind::Interpolant) e.kind = BlockKind::Spline;  // its control points
      e.reference = false;
      e.ownerStep = 0;
      e.chainLength = 1;
      writer.add(e, control.data());
      ++stats.resolved;
    } else {  // one payload: its bytes, checked
      stored.resize(e.storedSize);
      layout::preadAll(file->nativeHandle(), stored.data(), e.storedSize, e.offset, run, where);
      if (crc32(stored.data(), stored.size()) != e.checksum)
        throw FormatError(where + ": payload checksum mismatch");
      e.reference = false;
      e.ownerStep = 0;
      writer.addStored(e, stored.data());
      ++stats.copied;
    }
    ++stats.models;
    if (e.kind != BlockKind::Empty) {
      lo = std::min(lo, e.minValue);
      hi = std::max(hi, e.maxValue);
    }
  }
  stats.bytesOut = writer.commit(lo, hi);
  return stats;
}

}  // namespace afam
