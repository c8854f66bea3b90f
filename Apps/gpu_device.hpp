// SPDX-License-Identifier: BSD-3-Clause
// `--device cpu|gpu` for afam render and afam replay. With gpu, the CUDA ray caster (CudaKernels,
// afam_cuda) replaces the Renderer's CPU casting; caching, LOD, culling and prefetching stay the
// Renderer's. Where the build has no CUDA (no AFAM_HAVE_CUDA), no usable GPU is present (CUDA
// error 35 without a driver), or device memory runs out, it says so on stderr and uses the CPU.
#pragma once

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "afam/cpu_raycaster.hpp"
#include "afam/errors.hpp"
#include "afam/renderer.hpp"
#if defined(AFAM_HAVE_CUDA)
#include "afam/cuda/gpu_renderer.hpp"
#endif

namespace afam::cli {

inline const char* deviceOptionHelp() {
  return "  --device cpu|gpu       ray caster (default cpu); gpu falls back to the CPU with a\n"
         "                         message when no usable GPU is present\n"
         "  --gpu-budget-mb M      GPU model pool size in MiB (default 2048)\n";
}

/// Keeps the GPU renderer alive while the Renderer uses it.
struct DeviceChoice {
  std::string used = "cpu";
  std::string description;
  std::shared_ptr<void> state;
};

/// Installs the caster for `device` ("cpu" or "gpu") on `renderer`; returns what is used.
inline DeviceChoice useDevice(Renderer& renderer, const std::string& device, long long budgetMiB) {
  DeviceChoice choice;
  if (device == "cpu") return choice;
  if (device != "gpu") throw InvalidArgument("--device must be cpu or gpu, not '" + device + "'");
  if (budgetMiB < 16) throw InvalidArgument("--gpu-budget-mb must be >= 16");
#if defined(AFAM_HAVE_CUDA)
  std::string why;
  if (!gpuAvailable(&why)) {
    std::fprintf(stderr, "afam: --device gpu: %s; rendering on the CPU\n", why.c_str());
    return choice;
  }
  std::shared_ptr<GpuRenderer> gpu;
  for (size_t budget = size_t(budgetMiB) << 20; !gpu && budget >= (size_t(16) << 20); budget /= 2) {
    try {
      gpu = std::make_shared<GpuRenderer>(budget);
    } catch (const GpuOutOfMemory& e) {
      std::fprintf(stderr, "afam: GPU pool of %zu MiB: %s; trying half\n", budget >> 20, e.what());
    }
  }
  if (!gpu) {
    std::fprintf(stderr, "afam: --device gpu: no GPU memory for a model pool; rendering on the CPU\n");
    return choice;
  }
  const int threads = renderer.options().threads;
  auto warned = std::make_shared<bool>(false);
  renderer.setRayCaster([gpu, threads, warned](const PreparedFrame& frame, ImageRGBA& image) {
    image.resize(frame.view.camera.width, frame.view.camera.height);
    std::vector<uint64_t> keys(frame.entries.begin(), frame.entries.end());
    try {
      gpu->render(frame.view, keys.size() == size_t(frame.view.slotCount) ? keys.data() : nullptr,
                  image.rgba.data());
    } catch (const GpuOutOfMemory& e) {
      if (!*warned) std::fprintf(stderr, "afam: %s; this frame on the CPU\n", e.what());
      *warned = true;
      renderCpu(frame.view, image, threads);
    }
  });
  choice.used = "gpu";
  choice.description = gpuDescription(0);
  choice.state = gpu;
#else
  std::fprintf(stderr, "afam: --device gpu: this build has no CUDA support; rendering on the CPU\n");
#endif
  return choice;
}

}  // namespace afam::cli
