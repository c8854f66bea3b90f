// SPDX-License-Identifier: BSD-3-Clause
// Internal: turn a cudaError_t into afam::GpuError / afam::GpuOutOfMemory with file and line.
#pragma once

#include <cuda_runtime_api.h>

#include <string>

#include "afam/cuda/common/gpu_error.hpp"

namespace afam::cuda_detail {

[[noreturn]] inline void throwCudaError(cudaError_t status, const char* call, const char* file,
                                        int line) {
  const std::string name = cudaGetErrorName(status);
  std::string base = file;
  const auto slash = base.find_last_of('/');
  if (slash != std::string::npos) base = base.substr(slash + 1);
  const std::string message = "CUDA error " + name + " (" + std::to_string(int(status)) + ") at " +
                              base + ":" + std::to_string(line) + " in " + call + ": " +
                              cudaGetErrorString(status);
  if (status == cudaErrorMemoryAllocation)
    throw GpuOutOfMemory(message, base, line, name, int(status));
  throw GpuError(message, base, line, name, int(status));
}

}  // namespace afam::cuda_detail

#define AFAM_CUDA_CHECK(call)                                                      \
  do {                                                                             \
    const cudaError_t afamStatus_ = (call);                                        \
    if (afamStatus_ != cudaSuccess) {                                              \
      (void)cudaGetLastError(); /* clear a sticky-free error so later calls run */ \
      ::afam::cuda_detail::throwCudaError(afamStatus_, #call, __FILE__, __LINE__); \
    }                                                                              \
  } while (0)
