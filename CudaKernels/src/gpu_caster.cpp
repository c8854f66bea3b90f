// SPDX-License-Identifier: BSD-3-Clause
#include "afam/cuda/gpu_caster.hpp"

#include <vector>

#include "afam/render/cpu_raycaster.hpp"
#include "afam/render/device_selection.hpp"
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
  std::shared_ptr<GpuImageTarget> target = result.target;
  std::shared_ptr<bool> failed = result.failed;
  renderer.setRayCaster([gpu, threads, warned, report, target, failed](const PreparedFrame& frame,
                                                                       ImageRGBA& image) {
    const int w = frame.view.camera.width, h = frame.view.camera.height;
    const size_t floats = size_t(w) * size_t(h) * 4;
    std::vector<uint64_t> keys(frame.entries.begin(), frame.entries.end());
    const uint64_t* slotKeys = keys.size() == size_t(frame.view.slotCount) ? keys.data() : nullptr;
    const bool onDevice = target->deviceRgba && floats <= target->capacityFloats;
    const DeviceDepth* depth = target->depth.depth ? &target->depth : nullptr;
    target->lastOnDevice = false;
    target->lastDepthLimited = -1;
    FrameView view = frame.view;
    std::vector<float> hostLimits;
    auto limitsOnHost = [&] {  // a frame whose image goes through the host
      if (!depth || *failed) return;  // a failed GPU: this one frame ignores the device depth
      target->lastDepthLimited = gpu->depthLimitsToHost(*depth, hostLimits);
      view.maxDistance = hostLimits.data();
    };
    if (*failed) {  // known to fail: not tried again
      image.resize(w, h);
      renderCpu(view, image, threads);
      return;
    }
    try {
      if (onDevice) {
        gpu->renderToDevice(view, slotKeys, target->deviceRgba, nullptr, depth);
        target->lastDepthLimited = gpu->lastTimes().depthLimitedPixels;
        image.width = w;
        image.height = h;
        image.rgba.clear();
        target->lastOnDevice = true;
      } else {
        limitsOnHost();
        image.resize(w, h);
        gpu->render(view, slotKeys, image.rgba.data());
      }
    } catch (const GpuOutOfMemory& e) {
      if (!*warned) report(std::string(e.what()) + "; this frame on the CPU");
      *warned = true;
      if (hostLimits.empty()) limitsOnHost();
      image.resize(w, h);
      renderCpu(view, image, threads);
    } catch (const GpuError& e) {
      *failed = true;
      report(std::string("the GPU failed (") + e.what() + "); this frame and the next ones on the CPU");
      target->lastOnDevice = false;
      image.resize(w, h);
      renderCpu(view, image, threads);
    }
  });
  result.gpu = gpu;
  result.description = gpuDescription(gpu->pool().device());
  return result;
}

}  // namespace afam
