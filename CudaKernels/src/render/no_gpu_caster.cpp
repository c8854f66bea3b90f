// SPDX-License-Identifier: BSD-3-Clause
// makeGpuCaster of a build without nvcc: no GPU, and the reason in words.
#include "afam/cuda/render/make_gpu_caster.hpp"

namespace afam {

std::unique_ptr<FrameCaster> makeGpuCaster(size_t, int, const GpuReport& report,
                                           const std::optional<DeviceUuid>&) {
  report("this build has no CUDA renderer (built without nvcc)");
  return nullptr;
}

bool gpuCasterBuilt() { return false; }

}  // namespace afam
