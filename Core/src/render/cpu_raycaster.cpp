// SPDX-License-Identifier: BSD-3-Clause
#include "afam/render/cpu_raycaster.hpp"

namespace afam {

int resolveThreads(int requested) {
  if (requested > 0) return requested;
  const unsigned h = std::thread::hardware_concurrency();
  return h > 0 ? int(h) : 1;
}

void renderCpu(const FrameView& f, ImageRGBA& image, int threads) {
  renderCpuWith(f, ModelSampler{}, image, threads);
}

}  // namespace afam
