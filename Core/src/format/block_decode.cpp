// SPDX-License-Identifier: BSD-3-Clause
#include "afam/format/block_decode.hpp"

#include <cstring>
#include <limits>
#include <string>

#include "afam/base/errors.hpp"
#include "afam/format/block_mask.hpp"
#include "afam/spline/fit.hpp"

namespace afam {

void decodeBlockSamples(const ModelEntry& e, const float* payload, EncodingMode mode,
                        std::vector<float>& out) {
  const Int3 n = e.samples;
  if (mode == EncodingMode::Downsampled) {
    out.resize(size_t(n[0]) * size_t(n[1]) * size_t(n[2]));
    const size_t gx = size_t(e.ncp[0]), gy = size_t(e.ncp[1]);
    for (int z = 0; z < n[2]; ++z)
      for (int y = 0; y < n[1]; ++y)
        std::memcpy(out.data() + (size_t(z) * size_t(n[1]) + size_t(y)) * size_t(n[0]),
                    payload + ((size_t(z) + 1) * gy + size_t(y) + 1) * gx + 1,
                    size_t(n[0]) * sizeof(float));
    return;
  }
  const size_t count = size_t(n[0]) * size_t(n[1]) * size_t(n[2]);
  if (e.kind == BlockKind::Empty) {
    out.assign(count, std::numeric_limits<float>::quiet_NaN());
    return;
  }
  FitResult model;
  model.ncp = e.ncp;
  model.degree = e.degree;
  model.control.assign(payload, payload + controlCount(e));
  evaluateOnGrid(model, n, out);
  if (!e.masked) return;
  const float* words = payload + controlCount(e);
  for (size_t i = 0; i < count; ++i)
    if (!maskBit(words, int64_t(i))) out[i] = std::numeric_limits<float>::quiet_NaN();
}

LevelGrid levelGrid(const Partition& part, int level) {
  if (level < 0 || level >= part.levels())
    throw InvalidArgument("level " + std::to_string(level) + " outside [0, " +
                          std::to_string(part.levels() - 1) + "]");
  LevelGrid g;
  const Int3 nb = part.blocksPerAxis(level);
  for (int a = 0; a < 3; ++a) {
    Int3 ijk{0, 0, 0};
    int64_t pos = 0;
    for (int i = 0; i < nb[a]; ++i) {
      ijk[a] = i;
      g.start[size_t(a)].push_back(pos);
      pos += part.extent(level, ijk).samples[a] - 1;
    }
    g.dims[a] = pos + 1;
  }
  return g;
}

}  // namespace afam
