// SPDX-License-Identifier: BSD-3-Clause
// Kernels with the "exact" floating-point contract (compile options in CMakeLists.txt).
#define AFAM_KERNEL_NS kernels_exact
#include "render/kernels.cuh"
