// SPDX-License-Identifier: BSD-3-Clause
// Which GPU a process renders on when several MPI ranks share a node with several GPUs: one GPU per
// rank, by the node-local rank the MPI launcher exports, and the GPU its OpenGL context runs on
// where that is known (CUDA-OpenGL interop needs the same GPU; EGL/GLX and CUDA may number devices
// differently, so they are matched by UUID). Pure logic (no CUDA), so it is tested on machines
// without a GPU; CudaKernels applies it (GpuCaster::create, behind makeGpuCaster).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace afam {

/// Reads an environment variable (std::getenv by default; tests pass their own).
using EnvironmentLookup = std::function<const char*(const char*)>;

/// The node-local rank from the launcher's environment: OMPI_COMM_WORLD_LOCAL_RANK (Open MPI),
/// MPI_LOCALRANKID (MPICH / Intel MPI), MV2_COMM_WORLD_LOCAL_RANK (MVAPICH2), SLURM_LOCALID (srun),
/// the first one set that is a non-negative integer; -1 when none is.
int localRankFromEnvironment(const EnvironmentLookup& env = {});

/// The CUDA device index for this process among deviceCount visible devices: AFAM_CUDA_DEVICE when
/// set to a valid index (an explicit choice wins), else the local rank modulo deviceCount, else 0.
/// With a launcher that already restricts each rank to one device (CUDA_VISIBLE_DEVICES per rank),
/// deviceCount is 1 and the answer is 0. Returns -1 when deviceCount < 1.
int selectGpuDevice(int deviceCount, const EnvironmentLookup& env = {});

/// A GPU's UUID, as CUDA (cudaDeviceProp::uuid) and OpenGL (GL_DEVICE_UUID_EXT) report it.
using DeviceUuid = std::array<uint8_t, 16>;

/// The node-local number of ranks from the launcher's environment (OMPI_COMM_WORLD_LOCAL_SIZE,
/// MPI_LOCALNRANKS, MV2_COMM_WORLD_LOCAL_SIZE); -1 when none is set.
int localSizeFromEnvironment(const EnvironmentLookup& env = {});

/// A device chosen, and why in words ("AFAM_CUDA_DEVICE", "the OpenGL context's GPU", ...).
struct GpuChoice {
  int device = -1;
  std::string why;
};

/// The CUDA device among `devices` (their UUIDs, in CUDA's order) for a process whose OpenGL
/// context runs on the GPU `openGl` (none: no context, or an OpenGL that does not say, such as an
/// old driver). AFAM_CUDA_DEVICE wins when valid. Else the OpenGL context's GPU where it is one of
/// `devices` and the process is alone on its node or that GPU is its local rank's own
/// (selectGpuDevice): interop then works. Where several ranks share a node and this rank's
/// OpenGL runs on another rank's GPU (all contexts on one GPU, ParaView's default), the rank keeps
/// its own GPU, so that N ranks cast on N GPUs (the driver carries each image across to the
/// OpenGL's GPU), and `why` says so and how to give each rank its own GPU for OpenGL. Else as
/// selectGpuDevice.
/// device -1 when `devices` is empty.
GpuChoice chooseGpuDevice(const std::vector<DeviceUuid>& devices,
                          const std::optional<DeviceUuid>& openGl,
                          const EnvironmentLookup& env = {});

}  // namespace afam
