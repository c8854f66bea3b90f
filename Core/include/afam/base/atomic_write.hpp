// SPDX-License-Identifier: BSD-3-Clause
// Whole small files written at once (trajectories, APPA tables): the bytes go to PATH.tmp, which
// is then renamed onto PATH, so a reader sees the old file or the new one, never half of one.
#pragma once

#include <cstddef>
#include <string>

namespace afam {

/// Writes `bytes` bytes to PATH.tmp and renames it onto `path`; on failure removes PATH.tmp and
/// throws IoError naming the file and `what` it holds (for example "trajectory").
void writeFileAtomically(const std::string& path, const void* data, std::size_t bytes,
                         const std::string& what);

}  // namespace afam
