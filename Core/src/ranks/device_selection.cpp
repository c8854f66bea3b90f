// SPDX-License-Identifier: BSD-3-Clause
#include "afam/ranks/device_selection.hpp"

#include <cstdlib>
#include <string>

namespace afam {

namespace {

const char* lookup(const EnvironmentLookup& env, const char* name) {
  return env ? env(name) : std::getenv(name);
}

/// A non-negative decimal integer below 2^20, or -1.
int parseIndex(const char* text) {
  if (!text || !*text) return -1;
  long v = 0;
  for (const char* p = text; *p; ++p) {
    if (*p < '0' || *p > '9') return -1;
    v = v * 10 + (*p - '0');
    if (v >= (1L << 20)) return -1;
  }
  return int(v);
}

}  // namespace

int localRankFromEnvironment(const EnvironmentLookup& env) {
  for (const char* name : {"OMPI_COMM_WORLD_LOCAL_RANK", "MPI_LOCALRANKID",
                           "MV2_COMM_WORLD_LOCAL_RANK", "SLURM_LOCALID"}) {
    const int rank = parseIndex(lookup(env, name));
    if (rank >= 0) return rank;
  }
  return -1;
}

int localSizeFromEnvironment(const EnvironmentLookup& env) {
  for (const char* name :
       {"OMPI_COMM_WORLD_LOCAL_SIZE", "MPI_LOCALNRANKS", "MV2_COMM_WORLD_LOCAL_SIZE"}) {
    const int size = parseIndex(lookup(env, name));
    if (size >= 1) return size;
  }
  return -1;
}

GpuChoice chooseGpuDevice(const std::vector<DeviceUuid>& devices,
                          const std::optional<DeviceUuid>& openGl, const EnvironmentLookup& env) {
  const int count = int(devices.size());
  if (count < 1) return {-1, "no CUDA device"};
  const int chosen = parseIndex(lookup(env, "AFAM_CUDA_DEVICE"));
  if (chosen >= 0 && chosen < count) return {chosen, "AFAM_CUDA_DEVICE"};
  const int rank = localRankFromEnvironment(env);
  const int own = rank >= 0 ? rank % count : 0;
  const std::string ownWhy = rank >= 0 ? "local rank " + std::to_string(rank) + "'s own GPU"
                                       : std::string("the first GPU");
  int gl = -1;
  if (openGl)
    for (int d = 0; d < count && gl < 0; ++d)
      if (devices[size_t(d)] == *openGl) gl = d;
  if (gl < 0) return {own, ownWhy};
  const int size = localSizeFromEnvironment(env);
  if (rank < 0 || size == 1 || gl == own) return {gl, "the OpenGL context's GPU"};
  return {own, ownWhy + " (its OpenGL runs on GPU " + std::to_string(gl) +
                   ": each image crosses to it; ParaView's --displays gives each rank its own)"};
}

int selectGpuDevice(int deviceCount, const EnvironmentLookup& env) {
  if (deviceCount < 1) return -1;
  const int chosen = parseIndex(lookup(env, "AFAM_CUDA_DEVICE"));
  if (chosen >= 0 && chosen < deviceCount) return chosen;
  const int rank = localRankFromEnvironment(env);
  return rank >= 0 ? rank % deviceCount : 0;
}

}  // namespace afam
