// SPDX-License-Identifier: BSD-3-Clause
#include "afam/encode_team.hpp"

#include <algorithm>

namespace afam {

RowShare rowShare(int rows, int rank, int size) {
  if (size < 1 || rank < 0 || rank >= size || rows < 1) return {};
  const int64_t n = rows, p = size, r = rank;
  return {int(n * r / p), int(n * (r + 1) / p)};
}

}  // namespace afam
