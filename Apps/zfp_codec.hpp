// SPDX-License-Identifier: BSD-3-Clause
// ZFP (Debian's libzfp 1.0) over a 3D float32 array, for the programs that compare codecs:
// `afam compare-codecs` and `afam_eval compress` share this one wrapper. The targets that link
// the `afam_zfp_codec` library get ZFP when CMake finds it; without it zfpAvailable() is false
// and zfpRoundTrip throws an afam::Error saying so.
#pragma once

#include <cstddef>

namespace afam {

enum class ZfpMode {
  FixedRate,      ///< parameter = bits per value
  FixedAccuracy,  ///< parameter = absolute error tolerance (ZFP uses the power of two at or below
                  ///< it)
};

struct ZfpRoundTrip {
  size_t bytes = 0;               ///< compressed stream bytes
  double effectiveParameter = 0;  ///< what ZFP applied (the rate or the power-of-two tolerance)
  double compressSeconds = 0, decompressSeconds = 0;
};

bool zfpAvailable();

/// Compresses nx * ny * nz floats (x fastest) into memory and decompresses them into `out`
/// (same size, may not alias `in`). threads > 1: compressed with ZFP's OpenMP execution on that
/// many threads (what a user's ZFP does on every core; ZFP decompresses serially in its variable
/// rate modes). Throws afam::Error when ZFP is not built in, has no OpenMP for threads > 1, or
/// fails, afam::InvalidArgument for a parameter <= 0, an empty array or threads < 1.
ZfpRoundTrip zfpRoundTrip(ZfpMode mode, double parameter, const float* in, size_t nx, size_t ny,
                          size_t nz, float* out, int threads = 1);

}  // namespace afam
