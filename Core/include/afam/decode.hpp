// SPDX-License-Identifier: BSD-3-Clause
// Decoding micro-models back to samples: one block on its own grid, or a box of one level.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "afam/afam_file.hpp"

namespace afam {

/// Samples of a decoded micro-block on its own n0 x n1 x n2 grid: the spline evaluated at the
/// sample parameters (B-spline modes) or the stored samples without the ghost layer (DS).
void decodeBlockSamples(const ModelEntry& entry, const float* payload, EncodingMode mode, std::vector<float>& out);

/// The sample grid of one decoded level: per axis the level's blocks' samples joined on their
/// shared boundary samples (dims), and where block i starts on each axis (start[a][i]).
struct LevelGrid {
  Index3 dims{};
  std::array<std::vector<int64_t>, 3> start;
};
LevelGrid levelGrid(const Partition& partition, int level);

/// Decodes level `level` of `file` inside the box [lo, hi] of its level grid (inclusive indices)
/// into `out`, x fastest, (hi - lo + 1) samples per axis. Reads only the blocks that own samples
/// of the box (a shared boundary sample belongs to the later block, as in `afam decode`).
/// `progress` (optional) gets fractions in [0, 1]. Throws InvalidArgument for a bad level or box.
/// A damaged block (checksum or decoding fails): with `damaged` null, its FormatError ends the
/// decode; with `damaged` given, its message is appended there and its samples are taken from
/// what a renderer draws in its place (damage.hpp: the nearest intact coarser model, else its
/// intact children), NaN where no intact model covers them. A file changed on disk since it was
/// opened (FileChangedError) ends the decode either way.
void decodeLevelBox(const AfamFile& file, int level, const Index3& lo, const Index3& hi, float* out,
                    const std::function<void(double)>& progress = {},
                    std::vector<std::string>* damaged = nullptr);

}  // namespace afam
