// SPDX-License-Identifier: BSD-3-Clause
// A volume whose work sits in one corner: a non-cubic grid (81 x 57 x 41) of air (0, the file's
// lowest value) around a smooth blob centred near one corner, encoded once per process with 3
// levels of 8 finest blocks per axis. The rank-box tests split it and draw it.
#pragma once

#include <unistd.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "afam/encode/encoder.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/volume/volume_source.hpp"
#include "scratch_dir.hpp"

namespace afam_test {

/// The blob's value at fractional position (fx, fy, fz) in [0, 1]^3: a smooth bump of radius
/// 0.35 around (0.72, 0.68, 0.3), rippled so that its blocks are splines; 0 outside.
inline float skewedBlobValue(double fx, double fy, double fz) {
  const double dx = fx - 0.72, dy = fy - 0.68, dz = fz - 0.3;
  const double r2 = (dx * dx + dy * dy + dz * dz) / (0.35 * 0.35);
  if (r2 >= 1) return 0.f;
  const double bump = (1 - r2) * (1 - r2);
  return float(bump * (0.75 + 0.25 * std::sin(9 * fx) * std::cos(7 * fy + 3 * fz)));
}

/// The blob encoded (once per process and name) at an RMSE bound: 1e-3 by default; another bound
/// and name give another file of the same volume.
inline std::shared_ptr<const afam::AfamFile> encodeSkewedBlob(
    double bound = 1e-3, const std::string& name = "skewed_blob.afam") {
  const std::string path = scratchPath(name);
  if (::access(path.c_str(), R_OK) != 0) {
    const afam::Index3 dims{81, 57, 41};
    std::vector<float> v(size_t(dims[0] * dims[1] * dims[2]));
    size_t i = 0;
    for (int64_t z = 0; z < dims[2]; ++z)
      for (int64_t y = 0; y < dims[1]; ++y)
        for (int64_t x = 0; x < dims[0]; ++x)
          v[i++] = skewedBlobValue(double(x) / double(dims[0] - 1), double(y) / double(dims[1] - 1),
                                   double(z) / double(dims[2] - 1));
    afam::ArraySource src(v.data(), dims);
    afam::EncoderOptions o;
    o.levels = 3;
    o.blocksPerAxis = 8;
    o.errorBound = bound;
    o.threads = 2;
    afam::encodeVolume(src, o, path);
  }
  return afam::AfamFile::open(path);
}

}  // namespace afam_test
