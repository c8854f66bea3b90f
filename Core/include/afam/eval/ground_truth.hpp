// SPDX-License-Identifier: BSD-3-Clause
// Analytic ground truth: the same castRay logic (raycast.hpp) sampling the Marschner-Lobb
// function and its exact gradient instead of micro-models. A volume from `afam ml --size N` holds
// ML sampled at lo + k (hi - lo)/(N - 1) on each axis, i.e. the normalised frame [-1, 1]^3 maps
// linearly onto the ML domain [lo, hi]^3; the sampler applies that map and scales the gradient
// back to the normalised frame (only its direction matters for shading).
#pragma once

#include "afam/base/host_device.hpp"
#include "afam/render/raycast.hpp"
#include "afam/volume/marschner_lobb.hpp"

namespace afam {

struct MarschnerLobbSampler {
  MarschnerLobb ml;

  template <bool WithGradient>
  AFAM_HD bool sample(const FrameView& f, const float* p, float& value, float* gradient) const {
    const float s = 0.5f * (ml.hi - ml.lo);  // domain units per normalised unit
    float q[3];
    for (int a = 0; a < 3; ++a) {
      const float pa = rc::clampf(p[a], f.boxLo[a], f.boxHi[a]);
      const float n = (pa - f.boxLo[a]) / (f.boxHi[a] - f.boxLo[a]) * 2.f - 1.f;  // [-1, 1]
      q[a] = ml.lo + (n + 1.f) * s;
    }
    value = ml.value(q[0], q[1], q[2]);
    if (WithGradient) {
      ml.gradient(q[0], q[1], q[2], gradient);
      for (int a = 0; a < 3; ++a) gradient[a] *= s * 2.f / (f.boxHi[a] - f.boxLo[a]);
    }
    return true;
  }
};

}  // namespace afam
