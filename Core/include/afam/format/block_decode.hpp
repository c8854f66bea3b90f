// SPDX-License-Identifier: BSD-3-Clause
// Decoding one micro-model back to the samples of its block, and the sample grid of a level.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "afam/format/afam_file.hpp"

namespace afam {

/// Samples of a decoded micro-block on its own n0 x n1 x n2 grid: the spline evaluated at the
/// sample parameters (B-spline modes) or the stored samples without the ghost layer (DS); NaN at
/// the missing samples of a masked model and everywhere in an empty block.
void decodeBlockSamples(const ModelEntry& entry, const float* payload, EncodingMode mode,
                        std::vector<float>& out);

/// The sample grid of one decoded level: per axis the level's blocks' samples joined on their
/// shared boundary samples (dims), and where block i starts on each axis (start[a][i]).
struct LevelGrid {
  Index3 dims{};
  std::array<std::vector<int64_t>, 3> start;
};
LevelGrid levelGrid(const Partition& partition, int level);

}  // namespace afam
