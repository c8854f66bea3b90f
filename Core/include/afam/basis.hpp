// SPDX-License-Identifier: BSD-3-Clause
// B-spline knots, span search and basis functions (with first derivatives), written once for the
// host and the device. Dependency-free on purpose: CudaKernels includes this header unchanged.
//
// Knots are implied by (ncp, degree) and never stored. For ncp control points of degree p the
// clamped knot vector has p+1 zeros, p+1 ones and ncp-p-1 interior knots placed by de Boor's knot
// averaging over ncp virtual uniform parameters v_k = k/(ncp-1):
//     t[p+j] = (j + (p-1)/2) / (ncp-1),   j = 1 .. ncp-p-1.
// The interior knots are therefore uniform (spacing h = 1/(ncp-1), offset c = (p-1)/(2(ncp-1))),
// so span search is O(1), and at ncp = n (interpolation of n uniform samples) the collocation
// matrix is the well-conditioned de Boor one, where plain uniform knots give cond ~ 1e9 for cubics
// at n = 128. For p = 1 this is exactly the uniform clamped vector.
#pragma once

#include "afam/host_device.hpp"

#if !defined(__CUDACC__)
#include <cmath>
#endif

namespace afam {

constexpr int kMaxDegree = 5;
constexpr int kMaxOrder = kMaxDegree + 1;

/// Knot vector implied by (ncp, degree); trivially copyable, usable on the device.
struct Knots {
  int ncp = 1;     ///< number of control points on this axis, >= degree+1
  int degree = 0;  ///< 0..kMaxDegree (0 only for one-sample axes)
  float offset = 0.f;  ///< c: position of interior knot j is c + j*h
  float spacing = 1.f; ///< h

  AFAM_HD static Knots make(int ncp_, int degree_) {
    Knots k;
    k.ncp = ncp_;
    k.degree = degree_;
    if (ncp_ > 1) {
      k.spacing = 1.0f / float(ncp_ - 1);
      k.offset = 0.5f * float(degree_ - 1) * k.spacing;
    } else {
      k.spacing = 1.f;
      k.offset = 0.f;
    }
    return k;
  }

  /// Knot t[i], i in [0, ncp+degree]; Real = double on the fitter, float in the ray casters.
  template <typename Real>
  AFAM_HD Real knot(int i) const {
    if (i <= degree) return Real(0);
    if (i >= ncp) return Real(1);
    const Real h = Real(1) / Real(ncp - 1);
    return Real(0.5) * Real(degree - 1) * h + Real(i - degree) * h;
  }

  /// Span index s in [degree, ncp-1] with t[s] <= u < t[s+1] (u = 1 maps to the last span).
  template <typename Real>
  AFAM_HD int span(Real u) const {
    const int last = ncp - degree - 1;  // number of interior knots
    int j = int(floor((u - Real(offset)) / Real(spacing)));
    j = j < 0 ? 0 : (j > last ? last : j);
    return degree + j;
  }
};

/// Clamp a parameter to [0, 1]; NaN maps to 0 so a bad coordinate never indexes out of range.
AFAM_HD float clampParameter(float u) {
  return u >= 0.f ? (u <= 1.f ? u : 1.f) : 0.f;
}

/// Non-zero basis functions of degree `deg` <= k.degree on span s of k's knot vector
/// (Cox-de Boor, The NURBS Book A2.2): N[r] = N_{s-deg+r, deg}(u), r = 0..deg.
template <typename Real>
AFAM_HD void basisOfDegree(const Knots& k, int s, Real u, int deg, Real* N) {
  Real left[kMaxOrder], right[kMaxOrder];
  N[0] = Real(1);
  for (int j = 1; j <= deg; ++j) {
    left[j] = u - k.knot<Real>(s + 1 - j);
    right[j] = k.knot<Real>(s + j) - u;
    Real saved = Real(0);
    for (int r = 0; r < j; ++r) {
      const Real denom = right[r + 1] + left[j - r];
      const Real temp = denom != Real(0) ? N[r] / denom : Real(0);
      N[r] = saved + right[r + 1] * temp;
      saved = left[j - r] * temp;
    }
    N[j] = saved;
  }
}

/// Non-zero basis functions N[0..p] of span s at u: N[i] = N_{s-p+i, p}(u).
template <typename Real>
AFAM_HD void basisFunctions(const Knots& k, int s, Real u, Real* N) {
  basisOfDegree(k, s, u, k.degree, N);
}

/// Basis functions N[0..p] and their first derivatives dN[0..p] with respect to u
/// (The NURBS Book eq. 2.9, from the degree p-1 functions on the same span).
template <typename Real>
AFAM_HD void basisFunctionsAndDerivatives(const Knots& k, int s, Real u, Real* N, Real* dN) {
  const int p = k.degree;
  if (p == 0) {
    N[0] = Real(1);
    dN[0] = Real(0);
    return;
  }
  Real lower[kMaxOrder];  // lower[r] = N_{s-p+1+r, p-1}(u)
  basisOfDegree(k, s, u, p - 1, lower);
  for (int i = 0; i <= p; ++i) {
    const int g = s - p + i;  // global index of basis function i
    const Real a = i >= 1 ? lower[i - 1] : Real(0);     // N_{g, p-1}
    const Real b = i <= p - 1 ? lower[i] : Real(0);     // N_{g+1, p-1}
    const Real da = k.knot<Real>(g + p) - k.knot<Real>(g);
    const Real db = k.knot<Real>(g + p + 1) - k.knot<Real>(g + 1);
    dN[i] = Real(p) * ((da != Real(0) ? a / da : Real(0)) - (db != Real(0) ? b / db : Real(0)));
  }
  basisOfDegree(k, s, u, p, N);
}

}  // namespace afam
