// SPDX-License-Identifier: BSD-3-Clause
// Decoding a box of one level back to samples, damaged blocks drawn as a renderer draws them
// (one block on its own grid: format/block_decode.hpp).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "afam/format/afam_file.hpp"
#include "afam/format/block_decode.hpp"

namespace afam {

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

/// Clamps `count` decoded values to the value range the source had (the file header's
/// valueMin..valueMax; NaN stays NaN): a spline's overshoot at a sharp edge then never shows as a
/// value the data never had (a front end's decoded level, whose range sets a colour map's).
void clampToSourceRange(const AfamFile& file, float* values, size_t count);

}  // namespace afam
