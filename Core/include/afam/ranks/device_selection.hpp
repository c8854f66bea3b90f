// SPDX-License-Identifier: BSD-3-Clause
// Which GPU a process renders on when several MPI ranks share a node with several GPUs: one GPU per
// rank, by the node-local rank the MPI launcher exports. Pure logic (no CUDA), so it is tested on
// machines without a GPU; CudaKernels applies it (GpuCaster::create, behind makeGpuCaster).
#pragma once

#include <functional>

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

}  // namespace afam
