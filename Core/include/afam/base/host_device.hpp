// SPDX-License-Identifier: BSD-3-Clause
// Host-device annotation shared by Core and CudaKernels. Empty without nvcc so that the same
// inline math compiles as plain C++17 for the CPU ray caster and as device code for the kernel.
#pragma once

#if defined(__CUDACC__)
#define AFAM_HD __host__ __device__ __forceinline__
#else
#define AFAM_HD inline
#endif
