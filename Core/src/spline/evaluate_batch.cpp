// SPDX-License-Identifier: BSD-3-Clause
#include "afam/spline/evaluate_batch.hpp"

namespace afam {
namespace {

constexpr int kBlock = 64;  // points per block: basis tables of a block stay in L1

// SIMD across points with GCC/Clang vector extensions: four lanes (SSE2 on baseline x86-64, NEON
// on ARM), and eight lanes in a copy compiled for AVX2 (not FMA) chosen at run time. Lane l
// performs exactly the scalar operations of point l, so the bits do not change. Everything below
// is force-inlined into the two entry points, so each is compiled for its own instruction set.
#define AFAM_BATCH_INLINE __attribute__((always_inline)) inline
// GCC and Clang warn that 32-byte vectors returned by functions without AVX change the ABI; all
// of those are force-inlined into the AVX2 entry point and never called across an ABI boundary.
#pragma GCC diagnostic ignored "-Wpsabi"

typedef float Vec4 __attribute__((vector_size(16)));
typedef int Vec4i __attribute__((vector_size(16)));
typedef float Vec8 __attribute__((vector_size(32)));
typedef int Vec8i __attribute__((vector_size(32)));

template <typename V>
AFAM_BATCH_INLINE V load(const void* p) {
  V v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}

/// Row (x0, x1, x2) of a point as four floats: one unaligned load (Padded: the caller checked
/// that x3 is in bounds) or three.
template <bool Padded>
AFAM_BATCH_INLINE Vec4 loadRow(const float* row) {
  return Padded ? load<Vec4>(row) : Vec4{row[0], row[1], row[2], 0.f};
}

/// A SIMD width: float and int lane vectors of kCount points.
template <typename FloatVector, typename IntVector, int Count>
struct LaneTypes {
  using F = FloatVector;
  using I = IntVector;
  static constexpr int kCount = Count;
};

/// Four lanes: one point per lane.
struct Lanes4 : LaneTypes<Vec4, Vec4i, 4> {
  /// Rows (x0, x1, x2) of the four points as three vectors (lane l = point l): a 4x4 transpose.
  template <bool Padded>
  static AFAM_BATCH_INLINE void rows(const float* const* row, int offset, F& r0, F& r1, F& r2) {
    const F p0 = loadRow<Padded>(row[0] + offset), p1 = loadRow<Padded>(row[1] + offset);
    const F p2 = loadRow<Padded>(row[2] + offset), p3 = loadRow<Padded>(row[3] + offset);
    const F t0 = __builtin_shufflevector(p0, p1, 0, 4, 1, 5);
    const F t1 = __builtin_shufflevector(p2, p3, 0, 4, 1, 5);
    const F t2 = __builtin_shufflevector(p0, p1, 2, 6, 3, 7);
    const F t3 = __builtin_shufflevector(p2, p3, 2, 6, 3, 7);
    r0 = __builtin_shufflevector(t0, t1, 0, 1, 4, 5);
    r1 = __builtin_shufflevector(t0, t1, 2, 3, 6, 7);
    r2 = __builtin_shufflevector(t2, t3, 0, 1, 4, 5);
  }
  /// (gu, gv, gw) of the four points interleaved into out[0..11].
  static AFAM_BATCH_INLINE void storeGradient(const F& gu, const F& gv, const F& gw, float* out) {
    const F uv01 = __builtin_shufflevector(gu, gv, 0, 4, 1, 5);
    const F vw12 = __builtin_shufflevector(gv, gw, 1, 5, 2, 6);
    const F uv33 = __builtin_shufflevector(gu, gv, 3, 7, 3, 7);
    const F g[3] = {__builtin_shufflevector(uv01, gw, 0, 1, 4, 2),
                    __builtin_shufflevector(vw12, gu, 0, 1, 6, 2),
                    __builtin_shufflevector(gw, uv33, 2, 4, 5, 3)};
    __builtin_memcpy(out, g, sizeof g);
  }
};

/// Eight lanes: two four-lane halves (points 0-3 and 4-7).
struct Lanes8 : LaneTypes<Vec8, Vec8i, 8> {
  template <bool Padded>
  static AFAM_BATCH_INLINE void rows(const float* const* row, int offset, F& r0, F& r1, F& r2) {
    Vec4 lo[3], hi[3];
    Lanes4::rows<Padded>(row, offset, lo[0], lo[1], lo[2]);
    Lanes4::rows<Padded>(row + 4, offset, hi[0], hi[1], hi[2]);
    r0 = __builtin_shufflevector(lo[0], hi[0], 0, 1, 2, 3, 4, 5, 6, 7);
    r1 = __builtin_shufflevector(lo[1], hi[1], 0, 1, 2, 3, 4, 5, 6, 7);
    r2 = __builtin_shufflevector(lo[2], hi[2], 0, 1, 2, 3, 4, 5, 6, 7);
  }
  static AFAM_BATCH_INLINE void storeGradient(const F& gu, const F& gv, const F& gw, float* out) {
    Lanes4::storeGradient(__builtin_shufflevector(gu, gu, 0, 1, 2, 3),
                          __builtin_shufflevector(gv, gv, 0, 1, 2, 3),
                          __builtin_shufflevector(gw, gw, 0, 1, 2, 3), out);
    Lanes4::storeGradient(__builtin_shufflevector(gu, gu, 4, 5, 6, 7),
                          __builtin_shufflevector(gv, gv, 4, 5, 6, 7),
                          __builtin_shufflevector(gw, gw, 4, 5, 6, 7), out + 12);
  }
};

/// Degree-2 span and basis (and derivatives) on one axis for `padded` parameters u[i], L::kCount
/// at a time, into structure-of-arrays tables: first[i] = (s_i - 2) * stride and
/// N[r][i] = N_{s_i-2+r}(u_i).
/// Lane by lane these are the operations of clampParameter, Knots::span and closedFormBasis<float>
/// for p = 2 (basis.hpp), in the same order, so the same bits; test_evaluate_batch.cpp asserts
/// it, and a change to that closed form must be mirrored here.
template <typename L, bool G>
AFAM_BATCH_INLINE void axisBlock2(const Knots& k, int stride, const float* u, int padded,
                                  int* first, float (*N)[kBlock], float (*dN)[kBlock]) {
  using F = typename L::F;
  using I = typename L::I;
  const int ncp = k.ncp;
  const float scale = float(ncp - 1), offset = k.offset;
  const float twoScale = 2.f * scale, dU = 4.f * scale, minusDU = -dU;
  const F zero = {}, one = zero + 1.f, endKnot = zero + float(2 * (ncp - 1));
  const I zeroI = {}, lastSpan = zeroI + (ncp - 3);
  const F lastSpanF = __builtin_convertvector(lastSpan, F);
  for (int i = 0; i < padded; i += L::kCount) {
    F x = load<F>(u + i);
    x = x >= zero ? (x <= one ? x : one) : zero;  // clampParameter (NaN -> 0)
    // Knots::span: j = trunc((u - offset) (ncp - 1)) clamped to [0, ncp - 3]; s = 2 + j.
    const F t = (x - offset) * scale;
    I j = t > zero ? __builtin_convertvector(t, I) : zeroI;
    j = j > lastSpan ? lastSpan : j;
    const I corner = j * stride;
    __builtin_memcpy(first + i, &corner, sizeof corner);
    // degree2KnotHalfUnits(k, s - 1 .. s + 2), knots in units of h/2: 0 up to t[2], 2 i - 3 on
    // the interior, 2 (ncp - 1) from t[ncp] on. Small integers, exact in float, as are their
    // differences and products below.
    const F jf = __builtin_convertvector(j, F), twoJ = jf + jf;
    const F k0 = jf > 1.f ? twoJ - 1.f : zero;
    const F k1 = jf > zero ? twoJ + 1.f : zero;
    const F k2 = jf >= lastSpanF ? endKnot : twoJ + 3.f;
    const F k3 = jf >= lastSpanF - 1.f ? endKnot : twoJ + 5.f;
    const F U = twoScale * x;
    const F a = k2 - U, b = U - k1;
    const F i0 = one / ((k2 - k0) * (k2 - k1));
    const F i2 = one / ((k3 - k1) * (k2 - k1));
    const F n0 = a * a * i0, n2 = b * b * i2;
    const F middle = one - n0 - n2;
    const F n1 = middle > zero ? middle : zero;
    __builtin_memcpy(N[0] + i, &n0, sizeof n0);
    __builtin_memcpy(N[1] + i, &n1, sizeof n1);
    __builtin_memcpy(N[2] + i, &n2, sizeof n2);
    if (G) {
      const F d0 = minusDU * a * i0, d2 = dU * b * i2;
      const F d1 = -(d0 + d2);
      __builtin_memcpy(dN[0] + i, &d0, sizeof d0);
      __builtin_memcpy(dN[1] + i, &d1, sizeof d1);
      __builtin_memcpy(dN[2] + i, &d2, sizeof d2);
    }
  }
}

/// Basis tables of a block (three axes).
struct BlockBasis {
  alignas(32) int first[3][kBlock];
  alignas(32) float N[3][3][kBlock];
  alignas(32) float dN[3][3][kBlock];
};

/// Degree-2 contraction of the L::kCount points starting at i; out = value, d/du, d/dv, d/dw.
template <typename L, bool G, bool Padded>
AFAM_BATCH_INLINE void contract(const float* const* corners, int nx, int ny, const BlockBasis& t,
                                int i, typename L::F* out) {
  using F = typename L::F;
  auto at = [i](const float(*table)[kBlock], int r) { return load<F>(table[r] + i); };
  const F nx0 = at(t.N[0], 0), nx1 = at(t.N[0], 1), nx2 = at(t.N[0], 2);
  F dnx0 = {}, dnx1 = {}, dnx2 = {};
  if (G) {
    dnx0 = at(t.dN[0], 0);
    dnx1 = at(t.dN[0], 1);
    dnx2 = at(t.dN[0], 2);
  }
  // The loop nest and operation order of detail::evaluateModelGeneric.
  F val = {}, gu = {}, gv = {}, gw = {};
  for (int c = 0; c <= 2; ++c) {
    F yzValue = {}, yzDu = {}, yzDv = {};
    for (int b = 0; b <= 2; ++b) {
      F r0, r1, r2;
      L::template rows<Padded>(corners, (c * ny + b) * nx, r0, r1, r2);
      F xValue = {};
      xValue += nx0 * r0;
      xValue += nx1 * r1;
      xValue += nx2 * r2;
      const F nyb = at(t.N[1], b);
      yzValue += nyb * xValue;
      if (G) {
        F xDu = {};
        xDu += dnx0 * r0;
        xDu += dnx1 * r1;
        xDu += dnx2 * r2;
        yzDu += nyb * xDu;
        yzDv += at(t.dN[1], b) * xValue;
      }
    }
    const F nzc = at(t.N[2], c);
    val += nzc * yzValue;
    if (G) {
      gu += nzc * yzDu;
      gv += nzc * yzDv;
      gw += at(t.dN[2], c) * yzValue;
    }
  }
  out[0] = val;
  out[1] = gu;
  out[2] = gv;
  out[3] = gw;
}

template <typename L, bool G>
AFAM_BATCH_INLINE void evaluateBlock(const ModelView& m, const float* uvw, int count, float* value,
                                     float* gradient) {
  using F = typename L::F;
  using I = typename L::I;
  constexpr int kLanes = L::kCount;
  // Parameters per axis; lanes past `count` evaluate u = 0 and are never stored.
  const int padded = (count + kLanes - 1) / kLanes * kLanes;
  alignas(32) float u[3][kBlock];
  for (int i = 0; i < count; ++i) {
    u[0][i] = uvw[3 * i];
    u[1][i] = uvw[3 * i + 1];
    u[2][i] = uvw[3 * i + 2];
  }
  for (int i = count; i < padded; ++i) u[0][i] = u[1][i] = u[2][i] = 0.f;
  BlockBasis t;
  const int nx = m.knots[0].ncp, ny = m.knots[1].ncp;
  const int stride[3] = {1, nx, nx * ny};
  for (int a = 0; a < 3; ++a)
    axisBlock2<L, G>(m.knots[a], stride[a], u[a], padded, t.first[a], t.N[a], t.dN[a]);
  // Corners whose 4-wide row loads could read past the last control point take 3-wide loads.
  const int lastSafeCorner = m.knots[2].ncp * ny * nx - 1 - ((2 * ny + 2) * nx + 3);
  for (int i = 0; i < padded; i += kLanes) {
    const I corner = load<I>(t.first[0] + i) + load<I>(t.first[1] + i) + load<I>(t.first[2] + i);
    const I outside = corner > lastSafeCorner;
    const float* corners[kLanes];
    bool inBounds = true;
    for (int l = 0; l < kLanes; ++l) {
      corners[l] = m.control + corner[l];
      inBounds = inBounds && outside[l] == 0;
    }
    F out[4];
    if (inBounds) {
      contract<L, G, true>(corners, nx, ny, t, i, out);
    } else {
      contract<L, G, false>(corners, nx, ny, t, i, out);
    }
    if (i + kLanes <= count) {
      __builtin_memcpy(value + i, &out[0], sizeof out[0]);
      if (G) L::storeGradient(out[1], out[2], out[3], gradient + 3 * i);
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

template <typename L, bool G>
AFAM_BATCH_INLINE void evaluateBlocked(const ModelView& m, const float* uvw, std::size_t n,
                                       float* value, float* gradient) {
  for (std::size_t i0 = 0; i0 < n; i0 += kBlock) {
    const int count = n - i0 < std::size_t(kBlock) ? int(n - i0) : kBlock;
    evaluateBlock<L, G>(m, uvw + 3 * i0, count, value + i0, G ? gradient + 3 * i0 : nullptr);
  }
}

template <bool G>
void evaluateDegree2Lanes4(const ModelView& m, const float* uvw, std::size_t n, float* value,
                           float* gradient) {
  evaluateBlocked<Lanes4, G>(m, uvw, n, value, gradient);
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define AFAM_BATCH_AVX2 1
template <bool G>
__attribute__((target("avx2"))) void evaluateDegree2Lanes8(const ModelView& m, const float* uvw,
                                                           std::size_t n, float* value,
                                                           float* gradient) {
  evaluateBlocked<Lanes8, G>(m, uvw, n, value, gradient);
}
#endif

template <bool G>
void evaluateDegree2(int lanes, const ModelView& m, const float* uvw, std::size_t n, float* value,
                     float* gradient) {
#if defined(AFAM_BATCH_AVX2)
  if (lanes == 8) return evaluateDegree2Lanes8<G>(m, uvw, n, value, gradient);
#endif
  (void)lanes;
  evaluateDegree2Lanes4<G>(m, uvw, n, value, gradient);
}

}  // namespace

int detail::batchLanes() {
#if defined(AFAM_BATCH_AVX2)
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (avx2) return 8;
#endif
  return 4;
}

void detail::evaluateModelBatchLanes(int lanes, const ModelView& m, const float* uvw, std::size_t n,
                                     float* value, float* gradient) {
  const int p = m.knots[0].degree;
  if (p == 2 && m.knots[1].degree == 2 && m.knots[2].degree == 2 && m.knots[0].ncp >= 3 &&
      m.knots[1].ncp >= 3 && m.knots[2].ncp >= 3) {
    if (gradient) {
      evaluateDegree2<true>(lanes, m, uvw, n, value, gradient);
    } else {
      evaluateDegree2<false>(lanes, m, uvw, n, value, nullptr);
    }
    return;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const float* x = uvw + 3 * i;
    value[i] = gradient ? evaluateModel<true>(m, x[0], x[1], x[2], gradient + 3 * i)
                        : evaluateModel<false>(m, x[0], x[1], x[2], nullptr);
  }
}

void evaluateModelBatch(const ModelView& m, const float* uvw, std::size_t n, float* value,
                        float* gradient) {
  detail::evaluateModelBatchLanes(detail::batchLanes(), m, uvw, n, value, gradient);
}

}  // namespace afam
