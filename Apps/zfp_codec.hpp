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
/// (same size, may not alias `in`), serially. Throws afam::Error when ZFP is not built in or fails,
/// afam::InvalidArgument for a parameter <= 0 or an empty array.
ZfpRoundTrip zfpRoundTrip(ZfpMode mode, double parameter, const float* in, size_t nx, size_t ny,
                          size_t nz, float* out);

}  // namespace afam
