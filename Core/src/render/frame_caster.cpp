// SPDX-License-Identifier: BSD-3-Clause
#include "afam/render/frame_caster.hpp"

#include "afam/render/cpu_raycaster.hpp"
#include "afam/render/renderer.hpp"

namespace afam {

CastResult CpuCaster::cast(const PreparedFrame& frame, const FrameTargets& targets,
                           ImageRGBA& image) {
  FrameView view = frame.view;
  view.maxDistance = targets.maxDistance;
  std::vector<float> pool;
  view.pool = frame.hostPool(pool);
  renderCpu(view, image, threads_);
  return CastResult{};
}

}  // namespace afam
