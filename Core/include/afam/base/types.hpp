// SPDX-License-Identifier: BSD-3-Clause
// Small value types shared across Core.
#pragma once

#include <array>

namespace afam {

/// Extents of a 3D grid or block (samples or control points per axis), x fastest.
struct Dims3 {
  int x = 1, y = 1, z = 1;
};

using Int3 = std::array<int, 3>;

}  // namespace afam
