// SPDX-License-Identifier: BSD-3-Clause
// Kernels with the "fast" floating-point contract (compile options in CMakeLists.txt).
#define AFAM_KERNEL_NS kernels_fast
#include "render/kernels.cuh"
