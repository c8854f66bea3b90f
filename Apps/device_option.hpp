// SPDX-License-Identifier: BSD-3-Clause
// `--device cpu|gpu` and `--gpu-budget-mb` for afam render, afam replay and afam_eval. With gpu,
// the caster makeGpuCaster returns (make_gpu_caster.hpp: the one place the GPU is set up) casts
// the Renderer's frames; caching, LOD, culling and prefetching stay the Renderer's. Where the
// build has no CUDA, no usable GPU is present (CUDA error 35 without a driver), or device memory
// runs out, it says so on stderr and uses the CPU.
#pragma once

#include <cstdio>
#include <string>

#include "afam/base/errors.hpp"
#include "afam/cuda/render/make_gpu_caster.hpp"
#include "afam/render/renderer.hpp"

namespace afam::cli {

inline const char* deviceOptionHelp() {
  return "  --device cpu|gpu       ray caster (default cpu); gpu falls back to the CPU with a\n"
         "                         message when no usable GPU is present\n"
         "  --gpu-budget-mb M      GPU model pool size in MiB (default 2048)\n";
}

/// What casts the frames: "cpu" or "gpu", and the GPU in words.
struct DeviceChoice {
  std::string used = "cpu";
  std::string description;
};

/// Gives `renderer` the caster for `device` ("cpu" or "gpu"); returns what is used.
inline DeviceChoice useDevice(Renderer& renderer, const std::string& device, long long budgetMiB) {
  DeviceChoice choice;
  if (device == "cpu") return choice;
  if (device != "gpu") throw InvalidArgument("--device must be cpu or gpu, not '" + device + "'");
  if (budgetMiB < 16) throw InvalidArgument("--gpu-budget-mb must be >= 16");
  std::unique_ptr<FrameCaster> gpu = makeGpuCaster(
      size_t(budgetMiB) << 20, renderer.resources().threads, [](const std::string& why) {
        std::fprintf(stderr, "afam: --device gpu: %s\n", why.c_str());
      });
  if (!gpu) {
    std::fprintf(stderr, "afam: --device gpu: rendering on the CPU\n");
    return choice;
  }
  choice.used = "gpu";
  choice.description = gpu->description();
  renderer.setCaster(std::move(gpu));
  return choice;
}

/// What the caster said during a frame (e.g. a pool too small for it), on stderr.
inline void printDeviceMessages(const FrameStats& stats) {
  for (const std::string& m : stats.cast.messages)
    std::fprintf(stderr, "afam: --device gpu: %s\n", m.c_str());
}

}  // namespace afam::cli
