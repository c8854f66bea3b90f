// SPDX-License-Identifier: BSD-3-Clause
// Volumes with holes, made from any volume for tests and benchmarks of missing samples: a ball cut
// out, a CT's circular field of view, and generated continents and sea floor (a land mask, as
// ocean models mark land), and the by-hand alternative users have today, the holes filled with the
// nearest valid value.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "afam/volume/volume_source.hpp"

namespace afam {

enum class MaskShape {
  Ball,         ///< a ball at the centre, radius a quarter of the shortest side
  FieldOfView,  ///< outside the cylinder along z inscribed in the xy-square (a CT's reconstruction)
  Land,         ///< generated continents (every depth) and a sea floor rising towards them
};
/// ball|fov|land; InvalidArgument otherwise.
MaskShape parseMaskShape(const std::string& name);

/// Which samples of a volume of `dims` a shape removes; deterministic (the land's relief from
/// `seed`).
class VolumeMask {
 public:
  VolumeMask(MaskShape shape, Index3 dims, uint64_t seed = 1);
  bool missing(int64_t x, int64_t y, int64_t z) const;

 private:
  MaskShape shape_;
  Index3 dims_;
  std::vector<float> relief_;  ///< Land: terrain height in [0, 1] per (x, y)
};

/// The inner source with the mask's samples read as `fill` (NaN by default: missing).
class MaskedSource : public WrappingSource {
 public:
  MaskedSource(VolumeSource& inner, const VolumeMask& mask,
               float fill = std::numeric_limits<float>::quiet_NaN());
  void readSlab(int64_t z0, int64_t zCount, float* out) override;

 private:
  const VolumeMask& mask_;
  float fill_;
};

/// Fills the NaN samples of a whole volume (x fastest) with the value of the nearest valid sample
/// in steps between face neighbours (a breadth-first search from every valid sample at once; ties
/// go to the first found). Throws InvalidArgument when no sample is valid.
void fillNearestValid(std::vector<float>& volume, Index3 dims);

}  // namespace afam
