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

int selectGpuDevice(int deviceCount, const EnvironmentLookup& env) {
  if (deviceCount < 1) return -1;
  const int chosen = parseIndex(lookup(env, "AFAM_CUDA_DEVICE"));
  if (chosen >= 0 && chosen < deviceCount) return chosen;
  const int rank = localRankFromEnvironment(env);
  return rank >= 0 ? rank % deviceCount : 0;
}

}  // namespace afam
