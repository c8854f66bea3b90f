// SPDX-License-Identifier: BSD-3-Clause
// Value and gradient of one tensor-product micro-model, written once for host and device.
#pragma once

#include <stdint.h>
#if !defined(__CUDACC__)
#include <cstring>
#endif

#include "afam/spline/basis.hpp"

namespace afam {

/// Non-owning view of one micro-model: implied knots per axis and its control points, x fastest,
/// index (iz * ny + iy) * nx + ix: float32 at control[index], or, for a model kept as codes
/// (codeWidth 1 or 2 bytes), control[codes[index]] (control is then the model's table of values:
/// an integer-coded model whose values take few distinct floats, kept in 1 or 2 bytes a point
/// instead of 4; the same floats). Trivially copyable, passed to kernels by value.
struct ModelView {
  Knots knots[3];
  const float* control = nullptr;
  const void* codes = nullptr;  ///< codeWidth-byte unsigned codes (codeWidth 0: none)
  int32_t codeWidth = 0;
};

namespace detail {

/// Control point readers: float32 points, or 1- and 2-byte codes into the model's table.
struct FloatPoints {
  const float* p;
  AFAM_HD float operator[](int64_t i) const { return p[i]; }
};
template <typename Code>
struct CodedPoints {
  const float* table;
  const unsigned char* codes;
  AFAM_HD float operator[](int64_t i) const {
    Code c;
#if defined(__CUDA_ARCH__)
    c = reinterpret_cast<const Code*>(codes)[i];
#else
    std::memcpy(&c, codes + i * int64_t(sizeof(Code)), sizeof(Code));  // bytes of a float array
#endif
    return table[c];
  }
};

#if defined(__CUDACC__)
#define AFAM_HD_FORCEINLINE AFAM_HD
#else
#define AFAM_HD_FORCEINLINE __attribute__((always_inline)) inline
#endif

/// The evaluation itself (control points read through `points`); evaluateModel below dispatches
/// to copies of it with the degree fixed and the points' storage known.
template <bool WithGradient, typename Points>
AFAM_HD_FORCEINLINE float evaluateModelGeneric(const ModelView& m, const Points& points, float u,
                                               float v, float w, float* gradient) {
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
      const int64_t row = (int64_t(sz - pz + c) * ny + (sy - py + b)) * nx + (sx - px);
      float xValue = 0.f, xDu = 0.f;
      for (int a = 0; a <= px; ++a) {
        const float cp = points[row + a];
        xValue += Nx[a] * cp;
        if (WithGradient) xDu += dNx[a] * cp;
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
template <int P, bool WithGradient, typename Points>
inline float evaluateModelFixedDegree(const ModelView& m, const Points& points, float u, float v,
                                      float w, float* gradient) {
  ModelView f = m;
  f.knots[0].degree = P;
  f.knots[1].degree = P;
  f.knots[2].degree = P;
  return evaluateModelGeneric<WithGradient>(f, points, u, v, w, gradient);
}

/// evaluateModel for one storage of the control points.
template <bool WithGradient, typename Points>
AFAM_HD_FORCEINLINE float evaluateModelWith(const ModelView& m, const Points& points, float u,
                                            float v, float w, float* gradient) {
#if !defined(__CUDA_ARCH__)
  const int p = m.knots[0].degree;
  if (p == m.knots[1].degree && p == m.knots[2].degree) {
    switch (p) {
      case 1:
        return evaluateModelFixedDegree<1, WithGradient>(m, points, u, v, w, gradient);
      case 2:
        return evaluateModelFixedDegree<2, WithGradient>(m, points, u, v, w, gradient);
      case 3:
        return evaluateModelFixedDegree<3, WithGradient>(m, points, u, v, w, gradient);
      default:
        break;
    }
  }
#endif
  return evaluateModelGeneric<WithGradient>(m, points, u, v, w, gradient);
}

}  // namespace detail

/// Value at parameters (u, v, w) in [0, 1]^3 (clamped). When `gradient` is non-null it receives
/// the derivatives with respect to (u, v, w); the caller scales them to world units.
/// On the host, models of one degree 1..3 on all axes take a degree-specialised copy (about 3x
/// faster); device code specialises at the kernel level instead (CudaKernels/src/kernels.cuh).
/// ReadsCodes false promises float32 points (m.codeWidth 0): the code readers are not compiled in.
/// The CUDA kernels are built both ways: reading codes costs them registers (8% of a frame, H100),
/// so only frames whose GPU pool holds compact models launch the copy that reads them.
template <bool WithGradient, bool ReadsCodes = true>
AFAM_HD float evaluateModel(const ModelView& m, float u, float v, float w, float* gradient) {
  using detail::evaluateModelWith;
  if (ReadsCodes && m.codeWidth == 1)
    return evaluateModelWith<WithGradient>(
        m, detail::CodedPoints<uint8_t>{m.control, static_cast<const unsigned char*>(m.codes)}, u,
        v, w, gradient);
  if (ReadsCodes && m.codeWidth == 2)
    return evaluateModelWith<WithGradient>(
        m, detail::CodedPoints<uint16_t>{m.control, static_cast<const unsigned char*>(m.codes)}, u,
        v, w, gradient);
  return evaluateModelWith<WithGradient>(m, detail::FloatPoints{m.control}, u, v, w, gradient);
}

}  // namespace afam
