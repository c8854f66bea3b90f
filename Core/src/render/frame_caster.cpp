// SPDX-License-Identifier: BSD-3-Clause
#include "afam/render/frame_caster.hpp"

#include "afam/render/cpu_raycaster.hpp"
#include "afam/render/prepared_frame.hpp"

namespace afam {

CastResult CpuCaster::cast(const PreparedFrame& frame, const FrameTargets& targets,
                           ImageRGBA& image) {
  std::vector<float> pool;  // used only by a frame whose models are not all floats
  FrameView view = frame.hostView(pool);
  view.maxDistance = targets.maxDistance;
  renderCpu(view, image, threads_);
  return CastResult{};
}

}  // namespace afam
