// SPDX-License-Identifier: BSD-3-Clause
// Puts the CUDA ray caster into a Core Renderer (Renderer::setRayCaster): caching, LOD, culling
// and prefetching stay the Renderer's; only the casting of a prepared frame runs on the GPU. One
// place for every front end that offers a GPU switch (`afam render/replay --device gpu`, the VTK
// mapper's RenderDevice). Plain C++: no CUDA header.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <string>

#include "afam/cuda/gpu_renderer.hpp"
#include "afam/render/renderer.hpp"

namespace afam {

class GpuRenderer;

/// Where the caster leaves a frame's image. By default in the frame's ImageRGBA on the host. A
/// front end that can draw from device memory (the VTK mapper: an OpenGL buffer mapped into CUDA)
/// sets deviceRgba before a frame; a frame cast on the GPU then stays there, and its ImageRGBA
/// holds the size only (rgba empty). A frame cast on the CPU (pool too small) fills the ImageRGBA.
struct GpuImageTarget {
  float* deviceRgba = nullptr;  ///< device memory for the next frames; null: the host
  size_t capacityFloats = 0;    ///< floats at deviceRgba (a larger frame goes to the host)
  bool lastOnDevice = false;    ///< set by every frame: its image is at deviceRgba
  /// Optional depth buffer in device memory for the next frames (depth.depth null: none): the
  /// rays stop at its opaque geometry, limits computed on the GPU (also for a frame that ends up
  /// on the CPU), in place of the frame's own maxDistance.
  DeviceDepth depth;
  int64_t lastDepthLimited = -1;  ///< pixels the depth limited in the last frame; -1: no depth
};

/// What installGpuCaster did.
struct GpuCaster {
  std::shared_ptr<GpuRenderer> gpu;  ///< keep alive while the Renderer is used; null: CPU
  std::string description;           ///< "NVIDIA H200 (sm_90, ...)" when installed
  std::shared_ptr<GpuImageTarget> target = std::make_shared<GpuImageTarget>();
  /// Set when a frame's CUDA work failed for another reason than memory (e.g. a lost context): that
  /// frame and every later one are cast on the CPU (reported once), the GPU is not tried again.
  std::shared_ptr<bool> failed = std::make_shared<bool>(false);
  explicit operator bool() const { return gpu != nullptr; }
};

/// Tries the GPU for `renderer`: probes for a usable device, allocates a model pool of
/// `budgetBytes` (halving down to 16 MiB while device memory is short) and installs the caster.
/// Every reason to use the CPU goes to `report` in words, e.g. "no usable GPU: CUDA driver is
/// missing or too old (cudaErrorInsufficientDriver, 35)"; when it returns an empty GpuCaster the
/// renderer is untouched (CPU). A frame whose models exceed the pool is cast on the CPU (reported
/// once); a frame whose CUDA work fails otherwise is cast on the CPU, and so are all later frames
/// (GpuCaster::failed, reported once). Never throws for a missing, full or failing GPU.
GpuCaster installGpuCaster(Renderer& renderer, size_t budgetBytes,
                           const std::function<void(const std::string&)>& report);

}  // namespace afam
