// SPDX-License-Identifier: BSD-3-Clause
// What the CPU can run beyond the build's baseline, asked once at run time, and the attribute that
// compiles one function for it. Explicit dispatch (a plain branch on cpuHasAvx2) rather than
// target_clones: clones resolve through ifuncs while the program is still being relocated, which
// ThreadSanitizer's runtime does not survive.
#pragma once

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define AFAM_TARGET_AVX2 __attribute__((target("avx2")))
#define AFAM_HAVE_AVX2_PATH 1
#else
#define AFAM_TARGET_AVX2
#define AFAM_HAVE_AVX2_PATH 0
#endif

namespace afam {

/// True when this CPU runs AVX2 code (x86-64 with AVX2; false on other architectures).
inline bool cpuHasAvx2() {
#if AFAM_HAVE_AVX2_PATH
  static const bool avx2 = __builtin_cpu_supports("avx2");
  return avx2;
#else
  return false;
#endif
}

}  // namespace afam
