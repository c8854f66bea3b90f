// SPDX-License-Identifier: BSD-3-Clause
#include "afam/format/step_extract.hpp"

#include <vector>

#include "afam/base/errors.hpp"
#include "afam/format/afam_file.hpp"
#include "file_layout.hpp"

namespace afam {

ExtractStats extractStep(const std::string& run, int64_t step, const std::string& out) {
  const std::shared_ptr<const AfamFile> file = AfamFile::open(run, step);
  AfamWriter writer(out, file->header());
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
      e.integerCoded = false;
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
  }
  writer.commit();
  stats.bytesOut = writer.bytesWritten();
  return stats;
}

}  // namespace afam
