// SPDX-License-Identifier: BSD-3-Clause
// `--device cpu|gpu` for afam render and afam replay. With gpu, the CUDA ray caster (CudaKernels,
// afam_cuda) replaces the Renderer's CPU casting; caching, LOD, culling and prefetching stay the
// Renderer's. Where the build has no CUDA (no AFAM_HAVE_CUDA), no usable GPU is present (CUDA
// error 35 without a driver), or device memory runs out, it says so on stderr and uses the CPU.
#pragma once

#include <cstdio>
#include <memory>
#include <string>

#include "afam/render/cpu_raycaster.hpp"
#include "afam/base/errors.hpp"
#include "afam/render/renderer.hpp"
#if defined(AFAM_HAVE_CUDA)
#include "afam/cuda/gpu_caster.hpp"
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
  GpuCaster gpu = installGpuCaster(renderer, size_t(budgetMiB) << 20, [](const std::string& why) {
    std::fprintf(stderr, "afam: --device gpu: %s\n", why.c_str());
  });
  if (!gpu) {
    std::fprintf(stderr, "afam: --device gpu: rendering on the CPU\n");
    return choice;
  }
  choice.used = "gpu";
  choice.description = gpu.description;
  choice.state = gpu.gpu;
#else
  (void)renderer;
  std::fprintf(stderr, "afam: --device gpu: this build has no CUDA support; rendering on the CPU\n");
#endif
  return choice;
}

}  // namespace afam::cli
