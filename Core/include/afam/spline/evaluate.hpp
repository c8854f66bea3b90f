// SPDX-License-Identifier: BSD-3-Clause
// Value and gradient of one tensor-product micro-model, written once for host and device.
#pragma once

#include "afam/spline/basis.hpp"

namespace afam {

/// Non-owning view of one micro-model: implied knots per axis and float32 control points,
/// x fastest: control[(iz * ny + iy) * nx + ix]. Trivially copyable, passed to kernels by value.
struct ModelView {
  Knots knots[3];
  const float* control = nullptr;
};

namespace detail {

#if defined(__CUDACC__)
#define AFAM_HD_FORCEINLINE AFAM_HD
#else
#define AFAM_HD_FORCEINLINE __attribute__((always_inline)) inline
#endif

/// The evaluation itself; evaluateModel below dispatches to copies of it with the degree fixed.
template <bool WithGradient>
AFAM_HD_FORCEINLINE float evaluateModelGeneric(const ModelView& m, float u, float v, float w,
                                               float* gradient) {
  const Knots& kx = m.knots[0];
  const Knots& ky = m.knots[1];
  const Knots& kz = m.knots[2];
  u = clampParameter(u);
  v = clampParameter(v);
  w = clampParameter(w);
  const int sx = kx.span(u), sy = ky.span(v), sz = kz.span(w);
  float Nx[kMaxOrder], Ny[kMaxOrder], Nz[kMaxOrder];
  float dNx[kMaxOrder], dNy[kMaxOrder], dNz[kMaxOrder];
  if (WithGradient) {
    basisFunctionsAndDerivatives(kx, sx, u, Nx, dNx);
    basisFunctionsAndDerivatives(ky, sy, v, Ny, dNy);
    basisFunctionsAndDerivatives(kz, sz, w, Nz, dNz);
  } else {
    basisFunctions(kx, sx, u, Nx);
    basisFunctions(ky, sy, v, Ny);
    basisFunctions(kz, sz, w, Nz);
  }
  const int nx = kx.ncp, ny = ky.ncp;
  const int px = kx.degree, py = ky.degree, pz = kz.degree;
  float value = 0.f, gu = 0.f, gv = 0.f, gw = 0.f;
  for (int c = 0; c <= pz; ++c) {
    float yzValue = 0.f, yzDu = 0.f, yzDv = 0.f;
    for (int b = 0; b <= py; ++b) {
      const float* row = m.control + ((sz - pz + c) * ny + (sy - py + b)) * nx + (sx - px);
      float xValue = 0.f, xDu = 0.f;
      for (int a = 0; a <= px; ++a) {
        xValue += Nx[a] * row[a];
        if (WithGradient) xDu += dNx[a] * row[a];
      }
      yzValue += Ny[b] * xValue;
      if (WithGradient) {
        yzDu += Ny[b] * xDu;
        yzDv += dNy[b] * xValue;
      }
    }
    value += Nz[c] * yzValue;
    if (WithGradient) {
      gu += Nz[c] * yzDu;
      gv += Nz[c] * yzDv;
      gw += dNz[c] * yzValue;
    }
  }
  if (WithGradient && gradient) {
    gradient[0] = gu;
    gradient[1] = gv;
    gradient[2] = gw;
  }
  return value;
}

/// The same operations with the degree a compile-time constant: the basis and tensor loops unroll
/// and their arrays stay in registers (values identical to the generic path).
template <int P, bool WithGradient>
inline float evaluateModelFixedDegree(const ModelView& m, float u, float v, float w,
                                      float* gradient) {
  ModelView f = m;
  f.knots[0].degree = P;
  f.knots[1].degree = P;
  f.knots[2].degree = P;
  return evaluateModelGeneric<WithGradient>(f, u, v, w, gradient);
}

}  // namespace detail

/// Value at parameters (u, v, w) in [0, 1]^3 (clamped). When `gradient` is non-null it receives
/// the derivatives with respect to (u, v, w); the caller scales them to world units.
/// On the host, models of one degree 1..3 on all axes take a degree-specialised copy (about 3x
/// faster); device code specialises at the kernel level instead (CudaKernels/src/kernels.cuh).
template <bool WithGradient>
AFAM_HD float evaluateModel(const ModelView& m, float u, float v, float w, float* gradient) {
#if !defined(__CUDA_ARCH__)
  const int p = m.knots[0].degree;
  if (p == m.knots[1].degree && p == m.knots[2].degree) {
    switch (p) {
      case 1:
        return detail::evaluateModelFixedDegree<1, WithGradient>(m, u, v, w, gradient);
      case 2:
        return detail::evaluateModelFixedDegree<2, WithGradient>(m, u, v, w, gradient);
      case 3:
        return detail::evaluateModelFixedDegree<3, WithGradient>(m, u, v, w, gradient);
      default:
        break;
    }
  }
#endif
  return detail::evaluateModelGeneric<WithGradient>(m, u, v, w, gradient);
}

}  // namespace afam
