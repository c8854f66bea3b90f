// SPDX-License-Identifier: BSD-3-Clause
// Seconds of the steady clock since a time point: what the encoders report of their stages.
#pragma once

#include <chrono>

namespace afam {

inline double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace afam
