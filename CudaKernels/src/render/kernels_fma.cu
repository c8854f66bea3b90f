// SPDX-License-Identifier: BSD-3-Clause
// Kernels with the "fma" floating-point contract (compile options in CMakeLists.txt).
#define AFAM_KERNEL_NS kernels_fma
#include "render/kernels.cuh"
