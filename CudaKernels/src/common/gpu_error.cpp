// SPDX-License-Identifier: BSD-3-Clause
#include "afam/cuda/common/gpu_error.hpp"

#include "afam/ranks/device_selection.hpp"

#include <cuda_runtime_api.h>

#include <cstdio>
#include <cstring>
#include <vector>

namespace afam {

int gpuDeviceCount() {
  int count = 0;
  if (cudaGetDeviceCount(&count) != cudaSuccess) {
    (void)cudaGetLastError();
    return 0;
  }
  return count;
}

GpuChoice gpuChoice(const std::optional<DeviceUuid>& openGl) {
  std::vector<DeviceUuid> uuids(static_cast<size_t>(gpuDeviceCount()));
  for (size_t d = 0; d < uuids.size(); ++d) {
    cudaDeviceProp prop{};
    if (cudaGetDeviceProperties(&prop, int(d)) != cudaSuccess) (void)cudaGetLastError();
    std::memcpy(uuids[d].data(), prop.uuid.bytes, uuids[d].size());
  }
  return chooseGpuDevice(uuids, openGl);
}

bool gpuAvailable(std::string* why, const std::optional<DeviceUuid>& openGl) {
  int count = 0;
  const cudaError_t status = cudaGetDeviceCount(&count);
  if (status != cudaSuccess) {
    (void)cudaGetLastError();
    if (why) {
      const std::string name = cudaGetErrorName(status);
      if (status == cudaErrorInsufficientDriver)
        *why = "CUDA driver is missing or too old for this build (" + name + ", " +
               std::to_string(int(status)) + ")";
      else if (status == cudaErrorNoDevice)
        *why = "no CUDA device (" + name + ", " + std::to_string(int(status)) + ")";
      else
        *why = "CUDA is not usable: " + name + " (" + std::to_string(int(status)) +
               "): " + cudaGetErrorString(status);
    }
    return false;
  }
  if (count < 1) {
    if (why) *why = "no CUDA device";
    return false;
  }
  // A device may be listed but unusable (compute-prohibited, wrong architecture for this binary):
  // touch the context once, on the device this process will use (one per MPI rank), so that ranks
  // do not all open a context on device 0.
  const int device = gpuChoice(openGl).device;
  const cudaError_t chosen = cudaSetDevice(device);
  const cudaError_t touch = chosen != cudaSuccess ? chosen : cudaFree(nullptr);
  if (touch != cudaSuccess) {
    (void)cudaGetLastError();
    if (why)
      *why = "CUDA device " + std::to_string(device) +
             " is not usable: " + cudaGetErrorName(touch) + " (" + std::to_string(int(touch)) + ")";
    return false;
  }
  if (why) why->clear();
  return true;
}

std::string gpuDescription(int device) {
  cudaDeviceProp prop{};
  if (cudaGetDeviceProperties(&prop, device) != cudaSuccess) {
    (void)cudaGetLastError();
    return {};
  }
  char memory[32];
  std::snprintf(memory, sizeof(memory), "%.1f",
                double(prop.totalGlobalMem) / (1024.0 * 1024.0 * 1024.0));
  return std::string(prop.name) + " (sm_" + std::to_string(prop.major) +
         std::to_string(prop.minor) + ", " + std::to_string(prop.multiProcessorCount) + " SMs, " +
         memory + " GiB)";
}

}  // namespace afam
