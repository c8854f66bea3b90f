// SPDX-License-Identifier: BSD-3-Clause
#include "afam/encode/encode_team.hpp"

#include <algorithm>

namespace afam {

WorkShare workShare(int64_t count, int rank, int size) {
  if (size < 1 || rank < 0 || rank >= size || count < 1) return {};
  const int64_t p = size, r = rank;
  return {count * r / p, count * (r + 1) / p};
}

}  // namespace afam
