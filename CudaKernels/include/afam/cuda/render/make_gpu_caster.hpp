// SPDX-License-Identifier: BSD-3-Clause
// The one place a front end asks for the GPU: `afam render/replay --device gpu`, afam_eval and the
// VTK mapper's RenderDevice all call makeGpuCaster and hand what it returns to Renderer::setCaster.
// Declared in every build (target afam_gpu_caster): a build with nvcc links the CUDA caster
// (gpu_caster.cpp, afam::GpuCaster), one without links a stub that says so (no_gpu_caster.cpp),
// so callers need no #if. Plain C++: no CUDA header.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "afam/ranks/device_selection.hpp"
#include "afam/render/frame_caster.hpp"

namespace afam {

/// Takes the reasons, in words, why the GPU is not (or not fully) used.
using GpuReport = std::function<void(const std::string&)>;

/// A caster on this process's GPU (gpuChoice: one per MPI rank, the OpenGL context's GPU `openGl`
/// where that allows CUDA-OpenGL interop; device_selection.hpp) with a model pool of
/// `budgetBytes` (halved down to 16 MiB while device memory is short); frames it cannot cast on
/// the GPU go to the CPU on `threads` threads (0: all cores). Returns nullptr when no GPU is
/// usable, every reason given to `report` (e.g. "no usable GPU: CUDA driver is missing or too
/// old (cudaErrorInsufficientDriver, 35)", or "this build has no CUDA renderer (built without
/// nvcc)"). Never throws for a missing, full or failing GPU.
std::unique_ptr<FrameCaster> makeGpuCaster(size_t budgetBytes, int threads, const GpuReport& report,
                                           const std::optional<DeviceUuid>& openGl = {});

/// True when this build has the CUDA renderer (built with nvcc).
bool gpuCasterBuilt();

}  // namespace afam
