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

#include "afam/base/host_device.hpp"

#if !defined(__CUDACC__)
#include <cmath>
#endif

namespace afam {

constexpr int kMaxDegree = 5;
constexpr int kMaxOrder = kMaxDegree + 1;

/// Knot vector implied by (ncp, degree); trivially copyable, usable on the device.
struct Knots {
  int ncp = 1;          ///< number of control points on this axis, >= degree+1
  int degree = 0;       ///< 0..kMaxDegree (0 only for one-sample axes)
  float offset = 0.f;   ///< c: position of interior knot j is c + j*h
  float spacing = 1.f;  ///< h

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

  /// 1/(ncp-1) in Real; for float this is bit-identical to `spacing` (one correctly rounded
  /// division), so the float path reads it instead of dividing again.
  template <typename Real>
  AFAM_HD Real spacingAs() const {
    return sizeof(Real) == sizeof(float) ? Real(spacing)
                                         : (ncp > 1 ? Real(1) / Real(ncp - 1) : Real(1));
  }

  /// Knot t[i], i in [0, ncp+degree]; Real = double on the fitter, float in the ray casters.
  template <typename Real>
  AFAM_HD Real knot(int i) const {
    if (i <= degree) return Real(0);
    if (i >= ncp) return Real(1);
    const Real h = spacingAs<Real>();
    return Real(0.5) * Real(degree - 1) * h + Real(i - degree) * h;
  }

  /// Span index s in [degree, ncp-1] with t[s] <= u < t[s+1] (u = 1 maps to the last span).
  /// Truncation instead of floor: the two differ only below zero, which is clamped to 0 anyway
  /// (and floor would be a libm call on baseline x86-64). Multiplies by ncp-1 instead of
  /// dividing by the spacing; at a knot either neighbouring span gives the same value.
  template <typename Real>
  AFAM_HD int span(Real u) const {
    const int last = ncp - degree - 1;  // number of interior knots
    const Real x = (u - Real(offset)) * Real(ncp - 1);
    int j = x > Real(0) ? int(x) : 0;  // also maps NaN to 0
    j = j > last ? last : j;
    return degree + j;
  }
};

/// Clamp a parameter to [0, 1]; NaN maps to 0 so a bad coordinate never indexes out of range.
AFAM_HD float clampParameter(float u) { return u >= 0.f ? (u <= 1.f ? u : 1.f) : 0.f; }

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
      // Multiply by the reciprocal (not divide) so this matches the derivative path bit for bit.
      const Real temp = denom != Real(0) ? N[r] * (Real(1) / denom) : Real(0);
      N[r] = saved + right[r + 1] * temp;
      saved = left[j - r] * temp;
    }
    N[j] = saved;
  }
}

/// Position of implied knot t[i] in units of h/2 for degree 2 (an integer: t[i] = K h / 2).
AFAM_HD int degree2KnotHalfUnits(const Knots& k, int i) {
  return i <= 2 ? 0 : (i >= k.ncp ? 2 * (k.ncp - 1) : 2 * i - 3);
}

/// Closed-form basis (and derivative) without the recurrence, where the implied knots allow it:
///  * p = 1: every span (the knots are uniform);
///  * p = 2: every span, the clamped end spans included: with U = 2 u / h and the knots in units
///    of h/2 (integers K), N[0] = (K[s+1] - U)^2 / ((K[s+1] - K[s-1]) (K[s+1] - K[s])),
///    N[2] = (U - K[s])^2 / ((K[s+2] - K[s]) (K[s+1] - K[s])), N[1] = 1 - N[0] - N[2] (clamped at
///    0) (interior spans: both products are 8; the two spans at each clamped end: 9 and 15, 10 and
///    8, chosen by selects; only ncp < 6, where the ends meet, divides);
///  * p = 3: spans whose 2p surrounding knots are all interior (the cardinal cubic).
/// Returns false (and writes nothing) elsewhere; those take the Cox-de Boor recurrence.
/// Agrees with it to rounding (tested).
template <typename Real>
AFAM_HD bool closedFormBasis(const Knots& k, int s, Real u, Real* N, Real* dN) {
  const int p = k.degree;
  const Real scale = Real(k.ncp - 1);  // 1 / h
  if (p == 2) {
    if (k.ncp < 3) return false;
    int k1, k2;
    Real i0, i2;
    if (k.ncp >= 6) {
      // Selects only, no branch: interior spans (both knot products 8) and the two spans at each
      // clamped end (products 9 and 15, then 10 and 8, mirrored at the upper end) take the same
      // instructions, so GPU lanes on either side of a block's end spans do not diverge.
      const int fromLow = s - 2, fromHigh = k.ncp - 1 - s;
      const bool low = fromLow <= fromHigh;
      const int e = low ? fromLow : fromHigh;
      const Real inner = e == 0 ? Real(1) / Real(9) : Real(1) / Real(10);
      const Real outer = e == 0 ? Real(1) / Real(15) : Real(0.125);
      i0 = e >= 2 ? Real(0.125) : (low ? inner : outer);
      i2 = e >= 2 ? Real(0.125) : (low ? outer : inner);
      // degree2KnotHalfUnits(s) and (s + 1) without the clamps that cannot apply (s <= ncp - 1):
      // calling it instead cost 5 % on the H200 (view 200: 3.90 -> 4.10 ms).
      k1 = s <= 2 ? 0 : 2 * s - 3;
      k2 = s + 1 >= k.ncp ? 2 * (k.ncp - 1) : 2 * s - 1;
    } else {
      const int k0 = degree2KnotHalfUnits(k, s - 1), k3 = degree2KnotHalfUnits(k, s + 2);
      k1 = degree2KnotHalfUnits(k, s);
      k2 = degree2KnotHalfUnits(k, s + 1);
      i0 = Real(1) / Real((k2 - k0) * (k2 - k1));
      i2 = Real(1) / Real((k3 - k1) * (k2 - k1));
    }
    const Real U = Real(2) * scale * u;
    const Real a = Real(k2) - U, b = U - Real(k1);
    N[0] = a * a * i0;
    N[2] = b * b * i2;
    const Real middle = Real(1) - N[0] - N[2];
    N[1] = middle > Real(0) ? middle : Real(0);  // rounding can leave -1e-16 where N[1] = 0
    if (dN) {
      const Real dU = Real(4) * scale;  // da/du = -2 / h, so dN[0]/du = -4 a i0 / h
      dN[0] = -dU * a * i0;
      dN[2] = dU * b * i2;
      dN[1] = -(dN[0] + dN[2]);
    }
    return true;
  }
  if (p < 1 || p > 3) return false;
  if (p == 3 && (s < 2 * p || s + p > k.ncp - 1)) return false;
  Real t = (u - k.knot<Real>(s)) * scale;
  t = t > Real(0) ? (t < Real(1) ? t : Real(1)) : Real(0);  // rounding at the span's ends
  const Real t1 = Real(1) - t;
  if (p == 1) {
    N[0] = t1;
    N[1] = t;
    if (dN) {
      dN[0] = -scale;
      dN[1] = scale;
    }
  } else {
    const Real sixth = Real(1) / Real(6);
    const Real t2 = t * t, t12 = t1 * t1;
    N[0] = sixth * t12 * t1;
    N[3] = sixth * t2 * t;
    N[1] = sixth * (Real(3) * t2 * t - Real(6) * t2 + Real(4));
    N[2] = Real(1) - N[0] - N[1] - N[3];
    if (dN) {
      const Real half = Real(0.5);
      dN[0] = -half * t12 * scale;
      dN[3] = half * t2 * scale;
      dN[1] = (Real(1.5) * t2 - Real(2) * t) * scale;
      dN[2] = -(dN[0] + dN[1] + dN[3]);
    }
  }
  return true;
}

/// Non-zero basis functions N[0..p] of span s at u: N[i] = N_{s-p+i, p}(u).
template <typename Real>
AFAM_HD void basisFunctions(const Knots& k, int s, Real u, Real* N) {
  if (closedFormBasis<Real>(k, s, u, N, nullptr)) return;
  basisOfDegree(k, s, u, k.degree, N);
}

/// Basis functions N[0..p] and their first derivatives dN[0..p] with respect to u, in one
/// triangular pass (The NURBS Book A2.3, first derivative only): the degree p-1 functions, then
/// the last Cox-de Boor step whose inverted knot differences the derivative reuses
/// (p(p+1)/2 divisions in all; on a non-empty span every such difference is positive).
template <typename Real>
AFAM_HD void basisFunctionsAndDerivatives(const Knots& k, int s, Real u, Real* N, Real* dN) {
  const int p = k.degree;
  if (p == 0) {
    N[0] = Real(1);
    dN[0] = Real(0);
    return;
  }
  if (closedFormBasis<Real>(k, s, u, N, dN)) return;
  Real lower[kMaxOrder];     // degree p-1 functions N_{s-p+1+r, p-1}(u), r = 0..p-1
  Real inv[kMaxOrder] = {};  // 1 / (t[s+r+1] - t[s+r+1-p]), r = 0..p-1 (degree-p denominators)
  basisOfDegree(k, s, u, p - 1, lower);
  // Last step of Cox-de Boor (degree p-1 -> p), keeping the reciprocals for the derivative.
  {
    Real saved = Real(0);
    for (int r = 0; r < p; ++r) {
      const Real right = k.knot<Real>(s + r + 1) - u;     // right[r+1]
      const Real left = u - k.knot<Real>(s + r + 1 - p);  // left[p-r]
      const Real denom = right + left;
      inv[r] = denom != Real(0) ? Real(1) / denom : Real(0);
      const Real temp = lower[r] * inv[r];
      N[r] = saved + right * temp;
      saved = left * temp;
    }
    N[p] = saved;
  }
  // dN_r = p (N_{r-1,p-1} / (t[s+r] - t[s+r-p]) - N_{r,p-1} / (t[s+r+1] - t[s+r+1-p])).
  const Real deg = Real(p);
  dN[0] = -deg * lower[0] * inv[0];
  for (int r = 1; r < p; ++r) dN[r] = deg * (lower[r - 1] * inv[r - 1] - lower[r] * inv[r]);
  dN[p] = deg * lower[p - 1] * inv[p - 1];
}

}  // namespace afam
