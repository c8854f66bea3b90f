// SPDX-License-Identifier: BSD-3-Clause
// The Marschner-Lobb test function and its exact gradient, written once for host and device:
//   f(x,y,z) = (1 - sin(pi z/2) + alpha (1 + cos(2 pi fM cos(pi r/2)))) / (2 (1 + alpha)),
//   r = sqrt(x^2 + y^2),
// in the function's own coordinates, which span [-1, 1] on each axis; the domain [lo, hi]^3 is
// mapped onto [-1, 1]^3 linearly, so value() and gradient() take domain coordinates and the
// gradient is with respect to them (world units). Defaults: alpha = 0.25, fM = 6, [-1, 1]^3
// (the paper's text uses alpha = 0.05 on [0, 7]).
#pragma once

#include "afam/base/host_device.hpp"

#include <array>
#include <cstdint>
#if !defined(__CUDACC__)
#include <cmath>
#endif

namespace afam {

namespace ml_detail {
template <typename Real>
AFAM_HD Real sinR(Real x) {
#if defined(__CUDA_ARCH__)
  return sin(x);
#else
  return std::sin(x);
#endif
}
template <typename Real>
AFAM_HD Real cosR(Real x) {
#if defined(__CUDA_ARCH__)
  return cos(x);
#else
  return std::cos(x);
#endif
}
template <typename Real>
AFAM_HD Real sqrtR(Real x) {
#if defined(__CUDA_ARCH__)
  return sqrt(x);
#else
  return std::sqrt(x);
#endif
}
}  // namespace ml_detail

struct MarschnerLobb {
  float alpha = 0.25f;
  float fM = 6.f;
  float lo = -1.f, hi = 1.f;  ///< domain per axis, mapped onto [-1, 1]

  /// The function's own coordinates (X, Y, Z) in [-1, 1] of domain point (x, y, z), the scale s
  /// (d X / d x) and the radius r = sqrt(X^2 + Y^2), which it returns.
  template <typename Real>
  AFAM_HD Real unitCoordinates(Real x, Real y, Real z, Real& X, Real& Y, Real& Z, Real& s) const {
    s = Real(2) / (Real(hi) - Real(lo));
    X = (x - Real(lo)) * s - Real(1);
    Y = (y - Real(lo)) * s - Real(1);
    Z = (z - Real(lo)) * s - Real(1);
    return ml_detail::sqrtR(X * X + Y * Y);
  }

  /// Value at domain coordinates; Real = double for reference data, float in kernels.
  template <typename Real>
  AFAM_HD Real valueT(Real x, Real y, Real z) const {
    using namespace ml_detail;
    const Real pi = Real(3.14159265358979323846);
    Real X, Y, Z, s;
    const Real r = unitCoordinates(x, y, z, X, Y, Z, s);
    const Real a = Real(alpha);
    const Real rho = cosR(Real(2) * pi * Real(fM) * cosR(pi * r / Real(2)));
    return (Real(1) - sinR(pi * Z / Real(2)) + a * (Real(1) + rho)) / (Real(2) * (Real(1) + a));
  }

  /// Exact gradient at domain coordinates, with respect to domain coordinates; finite at r = 0.
  template <typename Real>
  AFAM_HD void gradientT(Real x, Real y, Real z, Real* g) const {
    using namespace ml_detail;
    const Real pi = Real(3.14159265358979323846);
    Real X, Y, Z, s;
    const Real r = unitCoordinates(x, y, z, X, Y, Z, s);
    const Real a = Real(alpha);
    const Real norm = Real(1) / (Real(2) * (Real(1) + a));
    // d rho / dr = pi^2 fM sin(2 pi fM cos(pi r/2)) sin(pi r/2); divided by r for d/dX = (.) X/r.
    const Real sinHalfOverR = r > Real(1e-6) ? sinR(pi * r / Real(2)) / r : pi / Real(2);
    const Real dRhoOverR =
        pi * pi * Real(fM) * sinR(Real(2) * pi * Real(fM) * cosR(pi * r / Real(2))) * sinHalfOverR;
    g[0] = norm * a * dRhoOverR * X * s;
    g[1] = norm * a * dRhoOverR * Y * s;
    g[2] = -norm * (pi / Real(2)) * cosR(pi * Z / Real(2)) * s;
  }

  AFAM_HD float value(float x, float y, float z) const { return valueT<float>(x, y, z); }
  AFAM_HD void gradient(float x, float y, float z, float* g) const { gradientT<float>(x, y, z, g); }
};

#if !defined(__CUDACC__) || defined(AFAM_HOST_FUNCTIONS)
/// Fills z-slices [z0, z0 + zCount) of a dims[0] x dims[1] x dims[2] grid spanning [lo, hi]^3
/// (sample k on an axis of N at lo + k (hi - lo)/(N - 1); N = 1 samples the centre), x fastest,
/// dims[0] * dims[1] * zCount floats. Evaluated in double, rounded once to float. Multi-threaded
/// over rows when the slab is large. Throws afam::InvalidArgument on bad sizes.
void marschnerLobbSlab(const MarschnerLobb& ml, std::array<int64_t, 3> dims, int64_t z0,
                       int64_t zCount, float* out);
#endif

}  // namespace afam
