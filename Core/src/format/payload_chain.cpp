// SPDX-License-Identifier: BSD-3-Clause
// A model decoded from a chain of payloads in time (format version 3, in-time coding 2): the
// independent payload, then each step's coded residual added in order. The reader and the run
// writer (which codes the next step against what a reader will decode) both come here, so that
// both sum the same floats in the same order.
#include <algorithm>
#include <cstring>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/base/thread_scratch.hpp"
#include "file_layout.hpp"

namespace afam {
namespace layout {

namespace {

/// One part's stored bytes, read and checked against its CRC.
const uint8_t* readPart(int fd, const std::string& path, const ModelEntry& e,
                        const PayloadPart& p) {
  const std::string block = Partition::blockName(e.level, e.block);
  uint8_t* buffer = threadScratch<uint8_t>(ScratchSlot::ChainStored, p.storedSize);
  preadAll(fd, buffer, p.storedSize, p.offset, path,
           "payload of " + block + " at step " + std::to_string(p.step));
  if (crc32(buffer, p.storedSize) != p.checksum)
    throw FormatError(path + ": payload checksum mismatch at " + block + " of step " +
                      std::to_string(p.step));
  return buffer;
}

}  // namespace

void decodeChain(int fd, const std::string& path, const ModelEntry& e,
                 const std::vector<PayloadPart>& chain, const float* previous, float* out) {
  if (chain.size() < 2) throw InvalidArgument(path + ": decodeChain of a model of one payload");
  const size_t count = e.size / sizeof(float);
  float* residual = threadScratch<float>(ScratchSlot::Residual, count);
  // From the model before the newest residual when the caller has it (the same floats a whole
  // chain sums to, as it was summed the same way), else from the chain's first payload.
  size_t first = 0;
  if (previous) {
    std::copy(previous, previous + count, out);
    first = chain.size() - 1;
  }
  for (size_t k = first; k < chain.size(); ++k) {
    const PayloadPart& p = chain[k];
    ModelEntry part = e;  // the model's kind and NCP, this payload's coding
    part.coded = p.coded;
    part.integerCoded = p.integerCoded;
    part.lanesCoded = p.lanesCoded;
    part.roundedPoints = p.roundedPoints;
    part.storedSize = p.storedSize;
    const std::string where =
        path + ": " + Partition::blockName(e.level, e.block) + " of step " + std::to_string(p.step);
    const uint8_t* bytes = readPart(fd, path, e, p);
    decodeStoredPayload(part, bytes, k == 0 ? out : residual, where);
    if (k == 0) continue;
    for (size_t i = 0; i < count; ++i) out[i] = out[i] + residual[i];
  }
}

}  // namespace layout
}  // namespace afam
