// SPDX-License-Identifier: BSD-3-Clause
#include "afam/evaluate_batch.hpp"

namespace afam {
namespace {

constexpr int kBlock = 64;  // points per block: basis tables of a block stay in L1

// Four points per SIMD vector (GCC/Clang vector extension: SSE2 on baseline x86-64, NEON on ARM).
// Lane l performs exactly the scalar operations of point l, so the bits do not change.
typedef float Vec4 __attribute__((vector_size(16)));
constexpr int kLanes = 4;

typedef int Vec4i __attribute__((vector_size(16)));

inline Vec4 loadRow(const float* p) {
  Vec4 v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}

inline Vec4i loadRow4i(const int* p) {
  Vec4i v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}

/// Degree-2 span and basis (and derivatives) on one axis for `padded` parameters u[i], four at a
/// time, into structure-of-arrays tables: first[i] = (s_i - 2) * stride and
/// N[r][i] = N_{s_i-2+r}(u_i).
/// Lane by lane these are the operations of clampParameter, Knots::span and closedFormBasis<float>
/// for p = 2 (basis.hpp), in the same order, so the same bits; test_evaluate_batch.cpp asserts
/// it, and a change to that closed form must be mirrored here.
template <bool G>
void axisBlock2(const Knots& k, int stride, const float* u, int padded, int* first,
                float (*N)[kBlock], float (*dN)[kBlock]) {
  const int ncp = k.ncp;
  const float scale = float(ncp - 1), offset = k.offset;
  const float twoScale = 2.f * scale, dU = 4.f * scale, minusDU = -dU;
  const Vec4 zero = {}, one = zero + 1.f, endKnot = zero + float(2 * (ncp - 1));
  const Vec4i zeroI = {}, lastSpan = zeroI + (ncp - 3);
  const Vec4 lastSpanF = __builtin_convertvector(lastSpan, Vec4);
  for (int i = 0; i < padded; i += kLanes) {
    Vec4 x = loadRow(u + i);
    x = x >= zero ? (x <= one ? x : one) : zero;  // clampParameter (NaN -> 0)
    // Knots::span: j = trunc((u - offset) (ncp - 1)) clamped to [0, ncp - 3]; s = 2 + j.
    const Vec4 t = (x - offset) * scale;
    Vec4i j = t > zero ? __builtin_convertvector(t, Vec4i) : zeroI;
    j = j > lastSpan ? lastSpan : j;
    const Vec4i corner = j * stride;
    __builtin_memcpy(first + i, &corner, sizeof corner);
    // degree2KnotHalfUnits(k, s - 1 .. s + 2), knots in units of h/2: 0 up to t[2], 2 i - 3 on
    // the interior, 2 (ncp - 1) from t[ncp] on. Small integers, exact in float, as are their
    // differences and products below.
    const Vec4 jf = __builtin_convertvector(j, Vec4), twoJ = jf + jf;
    const Vec4 k0 = jf > 1.f ? twoJ - 1.f : zero;
    const Vec4 k1 = jf > zero ? twoJ + 1.f : zero;
    const Vec4 k2 = jf >= lastSpanF ? endKnot : twoJ + 3.f;
    const Vec4 k3 = jf >= lastSpanF - 1.f ? endKnot : twoJ + 5.f;
    const Vec4 U = twoScale * x;
    const Vec4 a = k2 - U, b = U - k1;
    const Vec4 i0 = one / ((k2 - k0) * (k2 - k1));
    const Vec4 i2 = one / ((k3 - k1) * (k2 - k1));
    const Vec4 n0 = a * a * i0, n2 = b * b * i2;
    const Vec4 middle = one - n0 - n2;
    const Vec4 n1 = middle > zero ? middle : zero;
    __builtin_memcpy(N[0] + i, &n0, sizeof n0);
    __builtin_memcpy(N[1] + i, &n1, sizeof n1);
    __builtin_memcpy(N[2] + i, &n2, sizeof n2);
    if (G) {
      const Vec4 d0 = minusDU * a * i0, d2 = dU * b * i2;
      const Vec4 d1 = -(d0 + d2);
      __builtin_memcpy(dN[0] + i, &d0, sizeof d0);
      __builtin_memcpy(dN[1] + i, &d1, sizeof d1);
      __builtin_memcpy(dN[2] + i, &d2, sizeof d2);
    }
  }
}

/// Control points row[0..2] of four points as three vectors (lane l = point l): one unaligned
/// load per point and a 4x4 transpose. Reads row[3] too, so the caller checks it is in bounds.
template <bool Padded>
inline void loadRows(const float* const* rows, int offset, Vec4& r0, Vec4& r1, Vec4& r2) {
  Vec4 p[kLanes];
  for (int l = 0; l < kLanes; ++l) {
    const float* row = rows[l] + offset;
    p[l] = Padded ? loadRow(row) : Vec4{row[0], row[1], row[2], 0.f};
  }
  const Vec4 t0 = __builtin_shufflevector(p[0], p[1], 0, 4, 1, 5);
  const Vec4 t1 = __builtin_shufflevector(p[2], p[3], 0, 4, 1, 5);
  const Vec4 t2 = __builtin_shufflevector(p[0], p[1], 2, 6, 3, 7);
  const Vec4 t3 = __builtin_shufflevector(p[2], p[3], 2, 6, 3, 7);
  r0 = __builtin_shufflevector(t0, t1, 0, 1, 4, 5);
  r1 = __builtin_shufflevector(t0, t1, 2, 3, 6, 7);
  r2 = __builtin_shufflevector(t2, t3, 0, 1, 4, 5);
}

/// Degree-2 contraction of four points (lanes) whose bases start at Nx[a] + i etc.
template <bool G, bool Padded>
inline void contract4(const float* const* corners, int nx, int ny, const float (*Nx)[kBlock],
                      const float (*dNx)[kBlock], const float (*Ny)[kBlock],
                      const float (*dNy)[kBlock], const float (*Nz)[kBlock],
                      const float (*dNz)[kBlock], int i, Vec4* out) {
  auto at = [i](const float (*t)[kBlock], int r) { return loadRow(t[r] + i); };
  const Vec4 nx0 = at(Nx, 0), nx1 = at(Nx, 1), nx2 = at(Nx, 2);
  Vec4 dnx0 = {}, dnx1 = {}, dnx2 = {};
  if (G) {
    dnx0 = at(dNx, 0);
    dnx1 = at(dNx, 1);
    dnx2 = at(dNx, 2);
  }
  // The loop nest and operation order of detail::evaluateModelGeneric.
  Vec4 val = {}, gu = {}, gv = {}, gw = {};
  for (int c = 0; c <= 2; ++c) {
    Vec4 yzValue = {}, yzDu = {}, yzDv = {};
    for (int b = 0; b <= 2; ++b) {
      Vec4 r0, r1, r2;
      loadRows<Padded>(corners, (c * ny + b) * nx, r0, r1, r2);
      Vec4 xValue = {};
      xValue += nx0 * r0;
      xValue += nx1 * r1;
      xValue += nx2 * r2;
      const Vec4 nyb = at(Ny, b);
      yzValue += nyb * xValue;
      if (G) {
        Vec4 xDu = {};
        xDu += dnx0 * r0;
        xDu += dnx1 * r1;
        xDu += dnx2 * r2;
        yzDu += nyb * xDu;
        yzDv += at(dNy, b) * xValue;
      }
    }
    const Vec4 nzc = at(Nz, c);
    val += nzc * yzValue;
    if (G) {
      gu += nzc * yzDu;
      gv += nzc * yzDv;
      gw += at(dNz, c) * yzValue;
    }
  }
  out[0] = val;
  out[1] = gu;
  out[2] = gv;
  out[3] = gw;
}

template <int P, bool G>
void evaluateBlock(const ModelView& m, const float* uvw, int count, float* value,
                   float* gradient) {
  static_assert(P == 2, "the contraction is written for degree 2");
  // Parameters per axis; lanes past `count` evaluate u = 0 and are never stored.
  const int padded = (count + kLanes - 1) / kLanes * kLanes;
  alignas(16) float u[3][kBlock];
  for (int i = 0; i < count; ++i) {
    u[0][i] = uvw[3 * i];
    u[1][i] = uvw[3 * i + 1];
    u[2][i] = uvw[3 * i + 2];
  }
  for (int i = count; i < padded; ++i) u[0][i] = u[1][i] = u[2][i] = 0.f;
  alignas(16) int fx[kBlock], fy[kBlock], fz[kBlock];
  alignas(16) float Nx[P + 1][kBlock], Ny[P + 1][kBlock], Nz[P + 1][kBlock];
  alignas(16) float dNx[P + 1][kBlock], dNy[P + 1][kBlock], dNz[P + 1][kBlock];
  const int nx = m.knots[0].ncp, ny = m.knots[1].ncp;
  axisBlock2<G>(m.knots[0], 1, u[0], padded, fx, Nx, dNx);
  axisBlock2<G>(m.knots[1], nx, u[1], padded, fy, Ny, dNy);
  axisBlock2<G>(m.knots[2], nx * ny, u[2], padded, fz, Nz, dNz);
  // Corners whose 4-wide row loads could read past the last control point take 3-wide loads.
  const int lastSafeCorner = m.knots[2].ncp * ny * nx - 1 - ((P * ny + P) * nx + 3);
  for (int i = 0; i < padded; i += kLanes) {
    Vec4i corner = loadRow4i(fx + i) + loadRow4i(fy + i) + loadRow4i(fz + i);
    const Vec4i outside = corner > lastSafeCorner;
    long long outsideBits[2];
    __builtin_memcpy(outsideBits, &outside, sizeof outside);
    const float* corners[kLanes];
    for (int l = 0; l < kLanes; ++l) corners[l] = m.control + corner[l];
    Vec4 out[4];
    if ((outsideBits[0] | outsideBits[1]) == 0) {
      contract4<G, true>(corners, nx, ny, Nx, dNx, Ny, dNy, Nz, dNz, i, out);
    } else {
      contract4<G, false>(corners, nx, ny, Nx, dNx, Ny, dNy, Nz, dNz, i, out);
    }
    if (i + kLanes <= count) {
      __builtin_memcpy(value + i, &out[0], sizeof out[0]);
      if (G) {  // interleave (gu, gv, gw) of four points into three vectors
        const Vec4 gu = out[1], gv = out[2], gw = out[3];
        const Vec4 uv01 = __builtin_shufflevector(gu, gv, 0, 4, 1, 5);
        const Vec4 vw12 = __builtin_shufflevector(gv, gw, 1, 5, 2, 6);
        const Vec4 uv33 = __builtin_shufflevector(gu, gv, 3, 7, 3, 7);
        const Vec4 g[3] = {__builtin_shufflevector(uv01, gw, 0, 1, 4, 2),
                           __builtin_shufflevector(vw12, gu, 0, 1, 6, 2),
                           __builtin_shufflevector(gw, uv33, 2, 4, 5, 3)};
        __builtin_memcpy(gradient + 3 * i, g, sizeof g);
      }
    } else {
      for (int l = 0; l < count - i; ++l) {
        value[i + l] = out[0][l];
        if (G) {
          gradient[3 * (i + l)] = out[1][l];
          gradient[3 * (i + l) + 1] = out[2][l];
          gradient[3 * (i + l) + 2] = out[3][l];
        }
      }
    }
  }
}

template <int P, bool G>
void evaluateBlocked(const ModelView& m, const float* uvw, std::size_t n, float* value,
                     float* gradient) {
  for (std::size_t i0 = 0; i0 < n; i0 += kBlock) {
    const int count = n - i0 < std::size_t(kBlock) ? int(n - i0) : kBlock;
    evaluateBlock<P, G>(m, uvw + 3 * i0, count, value + i0, G ? gradient + 3 * i0 : nullptr);
  }
}

}  // namespace

void evaluateModelBatch(const ModelView& m, const float* uvw, std::size_t n, float* value,
                        float* gradient) {
  const int p = m.knots[0].degree;
  if (p == 2 && m.knots[1].degree == 2 && m.knots[2].degree == 2 && m.knots[0].ncp >= 3 &&
      m.knots[1].ncp >= 3 && m.knots[2].ncp >= 3) {
    if (gradient) {
      evaluateBlocked<2, true>(m, uvw, n, value, gradient);
    } else {
      evaluateBlocked<2, false>(m, uvw, n, value, nullptr);
    }
    return;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const float* x = uvw + 3 * i;
    value[i] = gradient ? evaluateModel<true>(m, x[0], x[1], x[2], gradient + 3 * i)
                        : evaluateModel<false>(m, x[0], x[1], x[2], nullptr);
  }
}

}  // namespace afam
