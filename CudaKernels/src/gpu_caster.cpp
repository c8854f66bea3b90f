// SPDX-License-Identifier: BSD-3-Clause
#include "afam/cuda/gpu_caster.hpp"

#include <vector>

#include "afam/cpu_raycaster.hpp"
#include "afam/device_selection.hpp"
#include "afam/cuda/gpu_renderer.hpp"

namespace afam {

GpuCaster installGpuCaster(Renderer& renderer, size_t budgetBytes,
                           const std::function<void(const std::string&)>& report) {
  GpuCaster result;
  std::string why;
  if (!gpuAvailable(&why)) {
    report("no usable GPU: " + why);
    return result;
  }
  // One GPU per MPI rank on a node with several (device_selection.hpp).
  const int device = selectGpuDevice(gpuDeviceCount());
  std::shared_ptr<GpuRenderer> gpu;
  const size_t minBudget = size_t(16) << 20;
  for (size_t budget = budgetBytes; !gpu && budget >= minBudget; budget /= 2) {
    try {
      gpu = std::make_shared<GpuRenderer>(budget, device);
    } catch (const GpuOutOfMemory& e) {
      report("GPU pool of " + std::to_string(budget >> 20) + " MiB: " + e.what() + "; trying half");
    } catch (const GpuError& e) {
      report(std::string("GPU unusable: ") + e.what());
      return result;
    }
  }
  if (!gpu) {
    report("no GPU memory for a model pool");
    return result;
  }
  const int threads = renderer.resources().threads;
  auto warned = std::make_shared<bool>(false);
  renderer.setRayCaster([gpu, threads, warned, report](const PreparedFrame& frame, ImageRGBA& image) {
    image.resize(frame.view.camera.width, frame.view.camera.height);
    std::vector<uint64_t> keys(frame.entries.begin(), frame.entries.end());
    try {
      gpu->render(frame.view, keys.size() == size_t(frame.view.slotCount) ? keys.data() : nullptr,
                  image.rgba.data());
    } catch (const GpuOutOfMemory& e) {
      if (!*warned) report(std::string(e.what()) + "; this frame on the CPU");
      *warned = true;
      renderCpu(frame.view, image, threads);
    }
  });
  result.gpu = gpu;
  result.description = gpuDescription(gpu->pool().device());
  return result;
}

}  // namespace afam
