// SPDX-License-Identifier: BSD-3-Clause
// makeGpuLevelSampler of a build without nvcc: none, and the reason in words.
#include "afam/cuda/encode/make_gpu_level_sampler.hpp"

namespace afam {

std::shared_ptr<LevelSampler> makeGpuLevelSampler(
    const std::function<void(const std::string&)>& report, int, size_t) {
  report("this build has no CUDA encoder (built without nvcc)");
  return nullptr;
}

}  // namespace afam
