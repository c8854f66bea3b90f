// SPDX-License-Identifier: BSD-3-Clause
// Errors of the CUDA back end and the "is there a usable GPU" probe. Plain C++: no CUDA header, so
// Apps and the VTK mapper can include it and catch afam::GpuError without nvcc.
#pragma once

#include <optional>
#include <string>

#include "afam/ranks/device_selection.hpp"

#include "afam/base/errors.hpp"

namespace afam {

/// A CUDA call failed. Carries where (file, line), the CUDA error name and code, so a user sees
/// e.g. "CUDA error cudaErrorInvalidValue (1) at gpu_renderer.cu:120 in cudaMemcpyAsync: ...".
class GpuError : public Error {
 public:
  GpuError(const std::string& message, std::string file, int line, std::string errorName, int code)
      : Error(message),
        file_(std::move(file)),
        line_(line),
        errorName_(std::move(errorName)),
        code_(code) {}
  const std::string& file() const { return file_; }
  int line() const { return line_; }
  const std::string& errorName() const { return errorName_; }
  int code() const { return code_; }

 private:
  std::string file_;
  int line_ = 0;
  std::string errorName_;
  int code_ = 0;
};

/// Device memory ran out (cudaMalloc failed, or the model pool cannot hold one frame's models under
/// its byte budget). Recoverable: retry with a smaller frame / larger budget, or take the CPU path.
class GpuOutOfMemory : public GpuError {
 public:
  using GpuError::GpuError;
};

/// True when a CUDA device can be used by this process. On false, `why` (if given) says why in
/// words, e.g. "CUDA driver is missing or too old (cudaErrorInsufficientDriver, 35)" or
/// "no CUDA device", so the caller can print it and take the CPU path. Never throws.
/// The device it touches is the one gpuChoice(openGl) picks for this process.
bool gpuAvailable(std::string* why = nullptr, const std::optional<DeviceUuid>& openGl = {});
/// CUDA devices visible to this process (0 when CUDA is unusable).
int gpuDeviceCount();
/// This process's CUDA device (chooseGpuDevice over the visible devices' UUIDs) for an OpenGL
/// context on the GPU `openGl` (none: no context, or not known).
GpuChoice gpuChoice(const std::optional<DeviceUuid>& openGl = {});

/// "NVIDIA H200 (sm_90, 132 SMs, 139.8 GiB)" for device `device`; "" when there is none.
std::string gpuDescription(int device = 0);

}  // namespace afam
