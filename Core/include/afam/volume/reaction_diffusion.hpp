// SPDX-License-Identifier: BSD-3-Clause
// A real simulation for time-series tests and benchmarks: Gray-Scott reaction-diffusion of two
// species on a periodic 3D grid, explicit Euler with the 7-point Laplacian,
//   u' = Du lap(u) - u v^2 + F (1 - u),   v' = Dv lap(v) + u v^2 - (F + k) v,
// started from u = 1, v = 0 with `seeds` cubes of v = 0.5, u = 0.25 at places drawn from `seed`.
// Patterns grow from the seeds and fill the grid over a few thousand iterations, each step
// changing only where the fronts are: what a slowly evolving simulation's run looks like. The
// same arguments give the same values bit for bit, on any number of threads (each cell's update
// reads only the iteration before, in a fixed order of operations).
#pragma once

#include <cstdint>
#include <vector>

#include "afam/volume/volume_source.hpp"

namespace afam {

struct GrayScottOptions {
  Index3 dims{64, 64, 64};
  double du = 0.16, dv = 0.08;  ///< diffusion rates (grid units, dt = 1)
  double feed = 0.035, kill = 0.060;
  int seeds = 6;
  uint64_t seed = 1;
  int threads = 0;  ///< 0: every core (grids under 2^20 cells: one); the values do not depend on it
};

class GrayScott {
 public:
  /// Throws InvalidArgument for dims < 3 or more than 2^31 samples, rates outside (0, 1/6],
  /// or no seed cube.
  explicit GrayScott(const GrayScottOptions& options);
  /// Advances `iterations` explicit steps.
  void advance(int iterations);
  /// The v species (the pattern), x fastest.
  const std::vector<float>& v() const { return v_; }
  Index3 dims() const { return o_.dims; }

 private:
  void stepPlanes(int64_t z0, int64_t z1);  ///< planes [z0, z1) of one iteration into nu_, nv_
  GrayScottOptions o_;
  std::vector<float> u_, v_, nu_, nv_;
};

}  // namespace afam
