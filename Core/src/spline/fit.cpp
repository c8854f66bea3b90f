// SPDX-License-Identifier: BSD-3-Clause
// Separable least-squares fitting and separable grid evaluation; see fit.hpp for the method.
#include "afam/spline/fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <sstream>
#include <string>
#include <type_traits>

#include "afam/base/cpu_features.hpp"
#include "afam/base/huge_pages.hpp"
#include "afam/spline/basis.hpp"

// The passes over a block's values (solve, energy, changeEnergy, evaluate) are compiled twice: for
// the build's baseline and, where the CPU has it, for AVX2 (twice the doubles a vector), chosen at
// run time. The same operations in the same order, and no FMA, so the same doubles either way.
// Their bodies and row kernels are inlined into both (a target's function inlines only what it
// is told to).
#define AFAM_FIT_INLINE __attribute__((always_inline)) inline

namespace afam {

int effectiveDegree(int degree, int samples) { return std::max(0, std::min(degree, samples - 1)); }

std::array<int, 3> clampNcp(int ncp, const std::array<int, 3>& samples,
                            const std::array<int, 3>& degrees) {
  std::array<int, 3> out{};
  for (int a = 0; a < 3; ++a) out[a] = std::max(degrees[a] + 1, std::min(ncp, samples[a]));
  return out;
}

double psnr(double rmse, double valueRange) {
  if (rmse == 0) return std::numeric_limits<double>::infinity();
  return 20.0 * std::log10(valueRange / rmse);
}

namespace {

constexpr const char* kAxisName[3] = {"x", "y", "z"};

/// One axis: collocation (span start and p+1 weights per sample) and the banded Cholesky factor
/// of the normal matrix A^T A, all in double.
struct AxisSystem {
  int n = 0, ncp = 0, p = 0;
  bool factored = false;
  std::vector<int> first;       ///< first control point of sample i's support (span - p)
  std::vector<double> weight;   ///< (p+1) basis values per sample
  std::vector<double> lower;    ///< L[j][k] at lower[j*(p+1) + k - j + p], k in [j-p, j]
  std::vector<double> invDiag;  ///< 1 / L[j][j]
  /// Column view of the collocation: control point j is supported by samples rowFirst[j] ..
  /// rowLast[j], their weights at columnWeight[columnOffset[j] ...] in sample order.
  std::vector<int> rowFirst, rowLast;
  std::vector<size_t> columnOffset;
  std::vector<double> columnWeight;

  double L(int j, int k) const { return lower[size_t(j) * size_t(p + 1) + size_t(k - j + p)]; }
};

double parameterOf(int i, int n) { return n > 1 ? double(i) / double(n - 1) : 0.0; }

/// The column view of the collocation (first[i] is non-decreasing, so a column's samples are
/// consecutive).
void buildColumns(AxisSystem& s) {
  const int w = s.p + 1;
  s.rowFirst.assign(size_t(s.ncp), s.n);
  s.rowLast.assign(size_t(s.ncp), -1);
  for (int i = 0; i < s.n; ++i)
    for (int r = 0; r < w; ++r) {
      const size_t j = size_t(s.first[size_t(i)] + r);
      s.rowFirst[j] = std::min(s.rowFirst[j], i);
      s.rowLast[j] = std::max(s.rowLast[j], i);
    }
  s.columnOffset.assign(size_t(s.ncp), 0);
  s.columnWeight.clear();
  for (int j = 0; j < s.ncp; ++j) {
    s.columnOffset[size_t(j)] = s.columnWeight.size();
    for (int i = s.rowFirst[size_t(j)]; i <= s.rowLast[size_t(j)]; ++i)
      s.columnWeight.push_back(s.weight[size_t(i) * size_t(w) + size_t(j - s.first[size_t(i)])]);
  }
}

void buildCollocation(AxisSystem& s, int n, int ncp, int p) {
  s.n = n;
  s.ncp = ncp;
  s.p = p;
  s.factored = false;
  const int w = p + 1;
  const Knots knots = Knots::make(ncp, p);
  s.first.assign(size_t(n), 0);
  s.weight.assign(size_t(n) * size_t(w), 0.0);
  // Span search in double (Knots::span works in the float offset/spacing the kernels use).
  const double h = ncp > 1 ? 1.0 / double(ncp - 1) : 1.0;
  const double c = 0.5 * double(p - 1) * h;
  const int lastInterior = ncp - p - 1;
  double N[kMaxOrder];
  for (int i = 0; i < n; ++i) {
    const double u = parameterOf(i, n);
    int j = ncp > 1 ? int(std::floor((u - c) / h)) : 0;
    j = std::max(0, std::min(j, lastInterior));
    const int span = p + j;
    basisFunctions<double>(knots, span, u, N);
    s.first[size_t(i)] = span - p;
    for (int r = 0; r < w; ++r) s.weight[size_t(i) * size_t(w) + size_t(r)] = N[r];
  }
  buildColumns(s);
}

void factorNormal(AxisSystem& s) {
  const int m = s.ncp, p = s.p, w = p + 1;
  std::vector<double> normal(size_t(m) * size_t(w), 0.0);  // same band layout as `lower`
  for (int i = 0; i < s.n; ++i) {
    const double* wi = &s.weight[size_t(i) * size_t(w)];
    const int f = s.first[size_t(i)];
    for (int a = 0; a < w; ++a)
      for (int b = 0; b <= a; ++b)  // row f+a, column f+b <= f+a
        normal[size_t(f + a) * size_t(w) + size_t(b - a + p)] += wi[a] * wi[b];
  }
  s.lower.assign(normal.size(), 0.0);
  s.invDiag.assign(size_t(m), 0.0);
  for (int j = 0; j < m; ++j) {
    const int k0 = std::max(0, j - p);
    for (int k = k0; k <= j; ++k) {
      double sum = normal[size_t(j) * size_t(w) + size_t(k - j + p)];
      for (int l = k0; l < k; ++l) sum -= s.L(j, l) * s.L(k, l);
      if (k < j) {
        s.lower[size_t(j) * size_t(w) + size_t(k - j + p)] = sum * s.invDiag[size_t(k)];
      } else {
        const double diag = normal[size_t(j) * size_t(w) + size_t(p)];
        if (!(sum > 1e-13 * diag)) {
          std::ostringstream msg;
          msg << "afam fit: normal matrix of the axis system (n=" << s.n << ", ncp=" << m
              << ", p=" << p << ") is singular at pivot " << j << " (" << sum << " of " << diag
              << ")";
          throw NumericError(msg.str());
        }
        const double l = std::sqrt(sum);
        s.lower[size_t(j) * size_t(w) + size_t(p)] = l;
        s.invDiag[size_t(j)] = 1.0 / l;
      }
    }
  }
  s.factored = true;
}

// ---- Row kernels: one operation applied to `len` contiguous values of each row (vectorised) ----

/// out rows [0, m) = A^T * in rows [0, n): out_j = sum_i A[i][j] in_i.
template <typename In>
AFAM_FIT_INLINE void applyTransposeRows(const AxisSystem& s, const In* in, size_t inStride,
                                        double* out, size_t outStride, size_t len) {
  // Column by column, in blocks of kBlock values summed in registers over the column's samples
  // (in sample order, from 0): each output is written once.
  constexpr size_t kBlock = 8;
  for (int j = 0; j < s.ncp; ++j) {
    const int i0 = s.rowFirst[size_t(j)], i1 = s.rowLast[size_t(j)];
    const double* wj = s.columnWeight.data() + s.columnOffset[size_t(j)];
    double* __restrict dst = out + size_t(j) * outStride;
    size_t c0 = 0;
    for (; c0 + kBlock <= len; c0 += kBlock) {
      double acc[kBlock] = {};
      for (int i = i0; i <= i1; ++i) {
        const In* __restrict src = in + size_t(i) * inStride + c0;
        const double a = wj[i - i0];
        for (size_t t = 0; t < kBlock; ++t) acc[t] += a * double(src[t]);
      }
      for (size_t t = 0; t < kBlock; ++t) dst[c0 + t] = acc[t];
    }
    for (; c0 < len; ++c0) {
      double acc = 0;
      for (int i = i0; i <= i1; ++i) acc += wj[i - i0] * double(in[size_t(i) * inStride + c0]);
      dst[c0] = acc;
    }
  }
}

/// In place: rows [0, m) <- (L L^T)^{-1} rows.
AFAM_FIT_INLINE void solveRows(const AxisSystem& s, double* x, size_t stride, size_t len) {
  const int m = s.ncp, p = s.p;
  for (int j = 0; j < m; ++j) {
    double* __restrict xj = x + size_t(j) * stride;
    for (int k = std::max(0, j - p); k < j; ++k) {
      const double l = s.L(j, k);
      const double* __restrict xk = x + size_t(k) * stride;
      for (size_t c = 0; c < len; ++c) xj[c] -= l * xk[c];
    }
    const double d = s.invDiag[size_t(j)];
    for (size_t c = 0; c < len; ++c) xj[c] *= d;
  }
  for (int j = m - 1; j >= 0; --j) {
    double* __restrict xj = x + size_t(j) * stride;
    for (int k = j + 1; k <= std::min(m - 1, j + p); ++k) {
      const double l = s.L(k, j);
      const double* __restrict xk = x + size_t(k) * stride;
      for (size_t c = 0; c < len; ++c) xj[c] -= l * xk[c];
    }
    const double d = s.invDiag[size_t(j)];
    for (size_t c = 0; c < len; ++c) xj[c] *= d;
  }
}

/// In place: rows [0, m) <- L^T rows, so that the squared norm of the result is x^T (A^T A) x.
AFAM_FIT_INLINE void multiplyFactorTransposeRows(const AxisSystem& s, double* x, size_t stride,
                                                 size_t len) {
  const int m = s.ncp, p = s.p;
  for (int j = 0; j < m; ++j) {
    double* __restrict xj = x + size_t(j) * stride;
    const double d = s.L(j, j);
    for (size_t c = 0; c < len; ++c) xj[c] *= d;
    for (int k = j + 1; k <= std::min(m - 1, j + p); ++k) {
      const double l = s.L(k, j);
      const double* __restrict xk = x + size_t(k) * stride;
      for (size_t c = 0; c < len; ++c) xj[c] += l * xk[c];
    }
  }
}

/// Makes v hold at least n values, growing only: by half at least, and at once to `block` (the
/// block's sample count, which no pass of its fits and evaluations exceeds), so that a search's
/// growing shapes map no new buffer. Pages of a buffer are faulted in (and zeroed) where a pass
/// first writes them: mapping more than a pass uses costs nothing. A buffer reused across shapes
/// is not filled or copied again.
void grow(HugePageVector<double>& v, size_t n, size_t block) {
  if (v.size() >= n) return;
  const size_t size = std::max({n, block, v.size() + v.size() / 2});
  v.clear();  // nothing to copy
  v.resize(size);
}

/// Sum of squares of n values, in four lanes (vectorised).
template <typename T>
AFAM_FIT_INLINE double sumSquares(const T* v, size_t n) {
  DoubleQuad lane = {0, 0, 0, 0};
  size_t i = 0;
  for (; i + 4 <= n; i += 4) {
    const DoubleQuad q = {double(v[i]), double(v[i + 1]), double(v[i + 2]), double(v[i + 3])};
    lane += q * q;
  }
  double sum = (lane[0] + lane[1]) + (lane[2] + lane[3]);
  for (; i < n; ++i) sum += double(v[i]) * double(v[i]);
  return sum;
}

/// out rows [0, n) = A * in rows [0, m): the model on the sample parameters of this axis.
template <typename In, typename Out>
AFAM_FIT_INLINE void evaluateRows(const AxisSystem& s, const In* in, size_t inStride, Out* out,
                                  size_t outStride, size_t len, double* scratch) {
  const int w = s.p + 1;
  for (int i = 0; i < s.n; ++i) {
    const double* wi = &s.weight[size_t(i) * size_t(w)];
    const int f = s.first[size_t(i)];
    if (w == 3) {  // degree 2: each output summed in registers, the same products in the same order
      const In* __restrict s0 = in + size_t(f) * inStride;
      const In* __restrict s1 = s0 + inStride;
      const In* __restrict s2 = s1 + inStride;
      const double a0 = wi[0], a1 = wi[1], a2 = wi[2];
      Out* __restrict dst = out + size_t(i) * outStride;
      for (size_t c = 0; c < len; ++c) {
        double v = a0 * double(s0[c]);
        v += a1 * double(s1[c]);
        v += a2 * double(s2[c]);
        dst[c] = Out(v);
      }
      continue;
    }
    double* __restrict acc = std::is_same<Out, double>::value
                                 ? reinterpret_cast<double*>(out + size_t(i) * outStride)
                                 : scratch;
    {
      const In* __restrict src = in + size_t(f) * inStride;
      const double a = wi[0];
      for (size_t c = 0; c < len; ++c) acc[c] = a * double(src[c]);
    }
    for (int r = 1; r < w; ++r) {
      const In* __restrict src = in + size_t(f + r) * inStride;
      const double a = wi[r];
      for (size_t c = 0; c < len; ++c) acc[c] += a * double(src[c]);
    }
    if (!std::is_same<Out, double>::value) {
      Out* __restrict dst = out + size_t(i) * outStride;
      for (size_t c = 0; c < len; ++c) dst[c] = Out(acc[c]);
    }
  }
}

/// dst[c * dstStride + r] = src[r * srcStride + c] for r, c < 4, in registers (two rounds of
/// shuffles).
AFAM_FIT_INLINE void transpose4x4(const double* src, size_t srcStride, double* dst,
                                  size_t dstStride) {
  // Whole-vector loads and stores through memcpy: unaligned, and no aliasing question.
  using Four = double __attribute__((vector_size(32)));
  Four a0, a1, a2, a3;
  std::memcpy(&a0, src, sizeof(Four));
  std::memcpy(&a1, src + srcStride, sizeof(Four));
  std::memcpy(&a2, src + 2 * srcStride, sizeof(Four));
  std::memcpy(&a3, src + 3 * srcStride, sizeof(Four));
  const Four t0 = __builtin_shufflevector(a0, a1, 0, 4, 2, 6);
  const Four t1 = __builtin_shufflevector(a0, a1, 1, 5, 3, 7);
  const Four t2 = __builtin_shufflevector(a2, a3, 0, 4, 2, 6);
  const Four t3 = __builtin_shufflevector(a2, a3, 1, 5, 3, 7);
  const Four d[4] = {
      __builtin_shufflevector(t0, t2, 0, 1, 4, 5), __builtin_shufflevector(t1, t3, 0, 1, 4, 5),
      __builtin_shufflevector(t0, t2, 2, 3, 6, 7), __builtin_shufflevector(t1, t3, 2, 3, 6, 7)};
  for (int r = 0; r < 4; ++r) std::memcpy(dst + r * dstStride, &d[r], sizeof(Four));
}

/// dst[c * rows + r] = src[r * cols + c]: a rows x cols matrix transposed, so that the lines along
/// x become the vectors of the row kernels.
template <typename In, typename Out>
AFAM_FIT_INLINE void transpose(const In* __restrict src, size_t rows, size_t cols,
                               Out* __restrict dst) {
  constexpr size_t kTile = 16;
  for (size_t r0 = 0; r0 < rows; r0 += kTile)
    for (size_t c0 = 0; c0 < cols; c0 += kTile) {
      const size_t r1 = std::min(rows, r0 + kTile), c1 = std::min(cols, c0 + kTile);
      size_t rq = r0, cq = c0;  // where the 4 x 4 blocks end
      if constexpr (std::is_same<In, double>::value && std::is_same<Out, double>::value) {
        rq = r0 + (r1 - r0) / 4 * 4;
        cq = c0 + (c1 - c0) / 4 * 4;
        for (size_t r = r0; r < rq; r += 4)
          for (size_t c = c0; c < cq; c += 4)
            transpose4x4(src + r * cols + c, cols, dst + c * rows + r, rows);
      }
      for (size_t r = r0; r < r1; ++r)  // what the blocks left: columns past cq, rows past rq
        for (size_t c = r < rq ? cq : c0; c < c1; ++c) dst[c * rows + r] = Out(src[r * cols + c]);
    }
}

/// Throws NumericError naming the first non-finite sample. The scan is branch-free (vectorised);
/// the slow search runs only when something is wrong.
void checkFinite(const float* samples, const std::array<int, 3>& n) {
  const size_t total = size_t(n[0]) * size_t(n[1]) * size_t(n[2]);
  int bad = 0;
  for (size_t i = 0; i < total; ++i) bad |= !(std::fabs(samples[i]) <= FLT_MAX);
  if (!bad) return;
  for (size_t i = 0; i < total; ++i) {
    if (!std::isfinite(samples[i])) {
      const size_t x = i % size_t(n[0]), y = (i / size_t(n[0])) % size_t(n[1]),
                   z = i / (size_t(n[0]) * size_t(n[1]));
      std::ostringstream msg;
      msg << "afam fit: sample (" << x << ", " << y << ", " << z << ") (flat index " << i
          << ") of the " << n[0] << " x " << n[1] << " x " << n[2] << " block is "
          << (std::isnan(samples[i]) ? "NaN" : "infinite")
          << "; non-finite samples cannot be fitted";
      throw NumericError(msg.str());
    }
  }
}

void validate(const std::array<int, 3>& n, const std::array<int, 3>& ncp,
              const std::array<int, 3>& degrees) {
  for (int a = 0; a < 3; ++a) {
    if (ncp[a] < degrees[a] + 1 || ncp[a] > n[a]) {
      std::ostringstream msg;
      msg << "afam fit: NCP " << ncp[a] << " on axis " << kAxisName[a] << " is outside ["
          << degrees[a] + 1 << ", " << n[a] << "] (" << n[a] << " samples, degree " << degrees[a]
          << ")";
      throw InvalidArgument(msg.str());
    }
  }
}

void validateSamples(const std::array<int, 3>& n) {
  for (int a = 0; a < 3; ++a) {
    if (n[a] < 1) {
      std::ostringstream msg;
      msg << "afam fit: block has " << n[a] << " samples on axis " << kAxisName[a]
          << " (at least 1 needed)";
      throw InvalidArgument(msg.str());
    }
  }
}

}  // namespace

InterpolationAxis interpolationAxis(int n, int p) {
  if (n < 1 || p < 0 || p > kMaxDegree || p > n - 1)
    throw InvalidArgument("afam fit: no interpolation of degree " + std::to_string(p) + " on " +
                          std::to_string(n) + " samples");
  AxisSystem s;
  buildCollocation(s, n, n, p);
  factorNormal(s);
  InterpolationAxis a;
  a.n = n;
  a.p = p;
  a.rowFirst = s.rowFirst;
  a.rowLast = s.rowLast;
  a.columnOffset.assign(s.columnOffset.begin(), s.columnOffset.end());
  a.columnWeight = s.columnWeight;
  a.lower = s.lower;
  a.invDiag = s.invDiag;
  return a;
}

namespace {
AFAM_TARGET_AVX2 double sumSquaresAvx2(const float* v, size_t n) { return sumSquares(v, n); }
}  // namespace

double sumOfSquares(const float* samples, std::array<int, 3> n) {
  const size_t count = size_t(n[0]) * size_t(n[1]) * size_t(n[2]);
  return cpuHasAvx2() ? sumSquaresAvx2(samples, count) : sumSquares(samples, count);
}

/// Lines of an x pass handled together (BlockFitter::Impl::lineTiles): a tile of 64 lines of up to
/// 130 values is 66 kB of doubles each way, in L2. Block-wide transposes instead (three passes
/// over the block's doubles, strides of powers of two): a 64^3 fit and error (bench_fit's
/// BM_FitBanded, H200 machine's host, fastest of 7) 1.5x slower at NCP 64 (4.79-5.10 against
/// 3.24-3.39 ms), 1.1x at NCP 32, within noise at NCP 8 and 16; an in-cache whole tile where the
/// lines fit in 512 kB gained nothing at NCP 16 and lost the NCP 32 gain.
constexpr size_t kLineTile = 64;

/// A range that decides nothing: the error is measured.
constexpr RmseRange kUndecided{0.0, std::numeric_limits<double>::infinity()};

struct BlockFitter::Impl {
  std::vector<std::unique_ptr<AxisSystem>> cache;
  // Two block-sized buffers for every pass: a solve's z pass into bufZ, its y pass into bufY, its
  // x pass (lineTiles) b into bufZ (x index slowest) and c into bufY (x fastest, in place), kept
  // there for energy(); an evaluation's x pass into bufY and y pass into bufZ. A thread touches two
  // block-sized sets of pages (each fresh page costs a fault and its clearing).
  HugePageVector<double> bufZ, bufY, plane;
  // The x passes' tiles of kLineTile lines (lineTiles): transposed in cache, not block-wide.
  std::vector<double> tileIn, tileOut;
  const std::vector<uint32_t>* valid = nullptr;  ///< setMask
  std::vector<float> grid;                       ///< the model on the grid, for masked errors

  /// Bounds the cache. Called before the three axis() look-ups of a fit or an evaluation, never
  /// between them: clearing inside axis() destroyed the system the caller's earlier reference
  /// pointed to (a segfault once an NCP search had used 64 shapes).
  void trimCache() {
    if (cache.size() + 3 > 64) cache.clear();  // encoders use a handful of shapes
  }

  /// A pass along x over `lines` lines of `from` values each (x fastest, src) into lines of `to`
  /// values each (x fastest, dst), kLineTile lines at a time: each tile transposed into tileIn (x
  /// index slowest, the lines the vectors), pass(l0, t, tileIn, tileOut) writes tileOut in that
  /// layout, which is transposed into dst. Each value's sums are those of a block-wide transpose.
  template <typename In, typename Pass>
  AFAM_FIT_INLINE void lineTiles(size_t lines, size_t from, size_t to, const In* src, Pass&& pass,
                                 double* dst) {
    tileIn.resize(from * kLineTile);
    tileOut.resize(to * kLineTile);
    for (size_t l0 = 0; l0 < lines; l0 += kLineTile) {
      const size_t t = std::min(kLineTile, lines - l0);
      transpose(src + l0 * from, t, from, tileIn.data());
      pass(l0, t, tileIn.data(), tileOut.data());
      transpose(tileOut.data(), to, t, dst + l0 * to);
    }
  }

  const AxisSystem& axis(int n, int ncp, int p, bool needFactor) {
    AxisSystem* found = nullptr;
    for (auto& s : cache)
      if (s->n == n && s->ncp == ncp && s->p == p) {
        found = s.get();
        break;
      }
    if (!found) {
      cache.push_back(std::make_unique<AxisSystem>());
      found = cache.back().get();
      buildCollocation(*found, n, ncp, p);
    }
    if (needFactor && !found->factored) factorNormal(*found);
    return *found;
  }

  /// The three axis systems of a fit, factored, after the checks on its arguments.
  struct Axes {
    const AxisSystem *x, *y, *z;
  };
  /// `checkSamples` false: the caller knows the samples are finite (their sum of squares is).
  Axes prepareFit(const float* samples, const std::array<int, 3>& n, const std::array<int, 3>& ncp,
                  int degree, bool checkSamples = true);

  /// The least-squares solve: b = A^T d in bufZ (x index slowest), the double solution c in bufY
  /// (x fastest) and its float32 control points in `out`; returns max |control point|.
  double solve(const Axes& a, const float* samples, const std::array<int, 3>& n, FitResult& out) {
    float largest;
    if (cpuHasAvx2())
      largest = solvePassesAvx2(a, samples, n, out);
    else
      largest = solvePasses(a, samples, n, out);
    if (!(largest <= FLT_MAX)) throwControlOverflow(n);
    out.error = ErrorStats{};
    out.errorMeasured = false;
    return double(largest);
  }
  AFAM_FIT_INLINE float solvePasses(const Axes& a, const float* samples,
                                    const std::array<int, 3>& n, FitResult& out);
  AFAM_TARGET_AVX2 float solvePassesAvx2(const Axes& a, const float* samples,
                                         const std::array<int, 3>& n, FitResult& out) {
    return solvePasses(a, samples, n, out);
  }

  /// c^T b = c^T (A^T A) c of the last solve().
  double energy(const std::array<int, 3>& ncp) const {
    return cpuHasAvx2() ? energyPassAvx2(ncp) : energyPass(ncp);
  }
  AFAM_FIT_INLINE double energyPass(const std::array<int, 3>& ncp) const;
  AFAM_TARGET_AVX2 double energyPassAvx2(const std::array<int, 3>& ncp) const {
    return energyPass(ncp);
  }

  /// e^T (A^T A) e for e = the difference of two models' control points (same shape).
  double changeEnergy(const std::array<int, 3>& n, const FitResult& a, const FitResult& b) {
    trimCache();
    const Axes axes{&axis(n[0], a.ncp[0], a.degree[0], true),
                    &axis(n[1], a.ncp[1], a.degree[1], true),
                    &axis(n[2], a.ncp[2], a.degree[2], true)};
    return cpuHasAvx2() ? changeEnergyPassesAvx2(axes, a, b) : changeEnergyPasses(axes, a, b);
  }
  AFAM_FIT_INLINE double changeEnergyPasses(const Axes& axes, const FitResult& a,
                                            const FitResult& b);
  AFAM_TARGET_AVX2 double changeEnergyPassesAvx2(const Axes& axes, const FitResult& a,
                                                 const FitResult& b) {
    return changeEnergyPasses(axes, a, b);
  }

  /// Separable evaluation. Either writes the grid (gridOut) or reduces it against samples (stats).
  void evaluate(const FitResult& model, const std::array<int, 3>& n, const float* samples,
                ErrorStats* stats, float* gridOut);
  AFAM_FIT_INLINE void evaluatePasses(const Axes& axes, const FitResult& model,
                                      const std::array<int, 3>& n, const float* samples,
                                      ErrorStats* stats, float* gridOut);
  AFAM_TARGET_AVX2 void evaluatePassesAvx2(const Axes& axes, const FitResult& model,
                                           const std::array<int, 3>& n, const float* samples,
                                           ErrorStats* stats, float* gridOut) {
    evaluatePasses(axes, model, n, samples, stats, gridOut);
  }

  [[noreturn]] __attribute__((noinline)) static void throwControlOverflow(
      const std::array<int, 3>& n);
};

BlockFitter::BlockFitter() : impl_(std::make_unique<Impl>()) {}
BlockFitter::~BlockFitter() = default;
BlockFitter::BlockFitter(BlockFitter&&) noexcept = default;
BlockFitter& BlockFitter::operator=(BlockFitter&&) noexcept = default;

FitResult BlockFitter::fit(const float* samples, std::array<int, 3> n, std::array<int, 3> ncp,
                           int degree, bool computeError) {
  FitResult out;
  fitInto(samples, n, ncp, degree, computeError, out);
  return out;
}

BlockFitter::Impl::Axes BlockFitter::Impl::prepareFit(const float* samples,
                                                      const std::array<int, 3>& n,
                                                      const std::array<int, 3>& ncp, int degree,
                                                      bool checkSamples) {
  validateSamples(n);
  if (degree < 1 || degree > kMaxDegree) {
    std::ostringstream msg;
    msg << "afam fit: degree " << degree << " is outside [1, " << kMaxDegree << "]";
    throw InvalidArgument(msg.str());
  }
  std::array<int, 3> p{};
  for (int a = 0; a < 3; ++a) p[a] = effectiveDegree(degree, n[a]);
  validate(n, ncp, p);
  if (!samples) throw InvalidArgument("afam fit: null sample pointer");
  if (checkSamples) checkFinite(samples, n);
  trimCache();
  Axes axes{};
  axes.x = &axis(n[0], ncp[0], p[0], true);
  axes.y = &axis(n[1], ncp[1], p[1], true);
  axes.z = &axis(n[2], ncp[2], p[2], true);
  return axes;
}

void BlockFitter::Impl::throwControlOverflow(const std::array<int, 3>& n) {
  std::ostringstream msg;
  msg << "afam fit: a control point of the " << n[0] << " x " << n[1] << " x " << n[2]
      << " block overflows float32 (samples too close to FLT_MAX)";
  throw NumericError(msg.str());
}

float BlockFitter::Impl::solvePasses(const Axes& a, const float* samples,
                                     const std::array<int, 3>& n, FitResult& out) {
  const AxisSystem &ax = *a.x, &ay = *a.y, &az = *a.z;
  const size_t nx = size_t(n[0]), ny = size_t(n[1]);
  const size_t mx = size_t(ax.ncp), my = size_t(ay.ncp), mz = size_t(az.ncp);
  const size_t planeSize = nx * ny, lines = my * mz, slab = mx * my;
  const size_t block = planeSize * size_t(n[2]);
  constexpr size_t kChunk = 256;  // columns per chunk, so that a chunk's rows stay in cache

  // b = A^T d, along z (whole xy-planes are the vectors), then y (per z-slab, x-rows), then x (in
  // tiles of x-lines transposed, line index fastest, so that they are the vectors).
  grow(bufZ, planeSize * mz, block);
  for (size_t c0 = 0; c0 < planeSize; c0 += kChunk)
    applyTransposeRows(az, samples + c0, planeSize, bufZ.data() + c0, planeSize,
                       std::min(kChunk, planeSize - c0));
  grow(bufY, nx * lines, block);
  for (size_t k = 0; k < mz; ++k)
    applyTransposeRows(ay, bufZ.data() + k * planeSize, nx, bufY.data() + k * nx * my, nx, nx);
  // Then x and x's solve, kLineTile lines at a time: a tile of bufY transposed (x slowest), its b
  // kept in bufZ (x index slowest, for energy(); the y pass has read bufZ), solved, and transposed
  // back into bufY in place (a tile's mx values a line land below the lines still to be read).
  lineTiles(
      lines, nx, mx, bufY.data(),
      [&](size_t l0, size_t t, double* in, double* b) {
        applyTransposeRows(ax, in, t, b, t, t);
        for (size_t j = 0; j < mx; ++j) std::copy_n(b + j * t, t, bufZ.data() + j * lines + l0);
        solveRows(ax, b, t, t);
      },
      bufY.data());

  // (Nz (x) Ny (x) Nx) c = b, one axis at a time on the mx my mz coefficients: x above, then z
  // and y on the control-point layout (x fastest) in bufY.
  for (size_t c0 = 0; c0 < slab; c0 += kChunk)
    solveRows(az, bufY.data() + c0, slab, std::min(kChunk, slab - c0));
  for (size_t k = 0; k < mz; ++k) solveRows(ay, bufY.data() + k * slab, mx, mx);

  out.ncp = {ax.ncp, ay.ncp, az.ncp};
  out.degree = {ax.p, ay.p, az.p};
  out.control.resize(mx * lines);
  // Eight lanes of |control point| maxima (max is exact in any order; NaN ignored as std::max
  // does).
  float* __restrict control = out.control.data();
  const double* __restrict c = bufY.data();
  using Eight = float __attribute__((vector_size(32)));
  Eight most = {0, 0, 0, 0, 0, 0, 0, 0};
  const size_t count = mx * lines;
  size_t i = 0;
  for (; i + 8 <= count; i += 8) {
    Eight v;
    for (int l = 0; l < 8; ++l) v[l] = float(c[i + size_t(l)]);
    std::memcpy(control + i, &v, sizeof v);
    const Eight magnitude = v < 0 ? -v : v;
    most = most < magnitude ? magnitude : most;
  }
  float largest = 0;
  for (int l = 0; l < 8; ++l) largest = std::max(largest, most[l]);
  for (; i < count; ++i) {
    control[i] = float(c[i]);
    largest = std::max(largest, std::fabs(control[i]));
  }
  return largest;
}

double BlockFitter::Impl::energyPass(const std::array<int, 3>& ncp) const {
  const size_t mx = size_t(ncp[0]), lines = size_t(ncp[1]) * size_t(ncp[2]);
  double lane[4] = {0, 0, 0, 0};
  for (size_t j = 0; j < mx; ++j) {
    const double* __restrict b = bufZ.data() + j * lines;
    for (size_t l = 0; l < lines; ++l) lane[l % 4] += b[l] * bufY[l * mx + j];
  }
  return (lane[0] + lane[1]) + (lane[2] + lane[3]);
}

double BlockFitter::Impl::changeEnergyPasses(const Axes& axes, const FitResult& a,
                                             const FitResult& b) {
  const AxisSystem &ax = *axes.x, &ay = *axes.y, &az = *axes.z;
  const size_t mx = size_t(a.ncp[0]), my = size_t(a.ncp[1]), mz = size_t(a.ncp[2]);
  const size_t slab = mx * my, lines = my * mz;
  const size_t block = size_t(ax.n) * size_t(ay.n) * size_t(az.n);
  grow(bufY, mx * lines, block);
  for (size_t i = 0; i < mx * lines; ++i) bufY[i] = double(a.control[i]) - double(b.control[i]);
  multiplyFactorTransposeRows(az, bufY.data(), slab, slab);
  for (size_t k = 0; k < mz; ++k) multiplyFactorTransposeRows(ay, bufY.data() + k * slab, mx, mx);
  grow(bufZ, mx * lines, block);
  transpose(bufY.data(), lines, mx, bufZ.data());  // x index slowest: the x-lines are the vectors
  multiplyFactorTransposeRows(ax, bufZ.data(), lines, lines);
  return sumSquares(bufZ.data(), mx * lines);
}

void BlockFitter::fitInto(const float* samples, std::array<int, 3> n, std::array<int, 3> ncp,
                          int degree, bool computeError, FitResult& out) {
  Impl& im = *impl_;
  const Impl::Axes axes = im.prepareFit(samples, n, ncp, degree);
  im.solve(axes, samples, n, out);
  if (computeError) measure(samples, n, out);
}

bool BlockFitter::decide(const RmseRange& range, double bound, const float* samples,
                         std::array<int, 3> n, FitResult& model) {
  if (range.lo > bound || range.hi <= bound) {
    model.error.rmse = range.lo > bound ? range.lo : range.hi;
    return range.hi <= bound;
  }
  measure(samples, n, model);
  return model.error.rmse <= bound;
}

bool BlockFitter::fitWithin(const float* samples, std::array<int, 3> n, std::array<int, 3> ncp,
                            int degree, double bound, double sumOfSquares, FitResult& out) {
  Impl& im = *impl_;
  const Impl::Axes axes = im.prepareFit(samples, n, ncp, degree, !std::isfinite(sumOfSquares));
  const double largest = im.solve(axes, samples, n, out);
  const RmseRange range = im.valid ? kUndecided
                                   : rmseRange(sumOfSquares, im.energy(ncp), largest,
                                               size_t(n[0]) * size_t(n[1]) * size_t(n[2]));
  return decide(range, bound, samples, n, out);
}

namespace {

/// largestMagnitude in eight lanes (max is exact in any order; NaN ignored as std::max does),
/// compiled also for AVX2 and chosen at run time.
__attribute__((always_inline)) inline float largestMagnitudeBody(const float* v, size_t count) {
  using Eight = float __attribute__((vector_size(32)));
  Eight most = {0, 0, 0, 0, 0, 0, 0, 0};
  size_t i = 0;
  for (; i + 8 <= count; i += 8) {
    Eight x;
    std::memcpy(&x, v + i, sizeof x);
    const Eight magnitude = x < 0 ? -x : x;
    most = most < magnitude ? magnitude : most;
  }
  float largest = 0;
  for (int l = 0; l < 8; ++l) largest = std::max(largest, most[l]);
  for (; i < count; ++i) largest = std::max(largest, std::fabs(v[i]));
  return largest;
}

AFAM_TARGET_AVX2 float largestMagnitudeAvx2(const float* v, size_t count) {
  return largestMagnitudeBody(v, count);
}

}  // namespace

float largestMagnitude(const float* v, size_t count) {
  return cpuHasAvx2() ? largestMagnitudeAvx2(v, count) : largestMagnitudeBody(v, count);
}

bool BlockFitter::changeWithin(const float* samples, std::array<int, 3> n, const FitResult& fitted,
                               FitResult& changed, double bound) {
  if (!fitted.errorMeasured || changed.ncp != fitted.ncp || changed.degree != fitted.degree ||
      changed.control.size() != fitted.control.size())
    throw InvalidArgument("afam changeWithin: needs a measured fit and a model of the same shape");
  validateSamples(n);
  validate(n, fitted.ncp, fitted.degree);
  const float largest = std::max(largestMagnitude(fitted.control.data(), fitted.control.size()),
                                 largestMagnitude(changed.control.data(), changed.control.size()));
  const RmseRange range =
      impl_->valid ? kUndecided
                   : changedRmseRange(fitted.error.rmse, impl_->changeEnergy(n, fitted, changed),
                                      largest, size_t(n[0]) * size_t(n[1]) * size_t(n[2]));
  changed.errorMeasured = false;
  changed.error = ErrorStats{};
  return decide(range, bound, samples, n, changed);
}

void BlockFitter::measure(const float* samples, std::array<int, 3> n, FitResult& model) {
  if (model.errorMeasured) return;
  model.error = error(samples, n, model);
  model.errorMeasured = true;
}

void BlockFitter::Impl::evaluate(const FitResult& model, const std::array<int, 3>& n,
                                 const float* samples, ErrorStats* stats, float* gridOut) {
  validateSamples(n);
  for (int a = 0; a < 3; ++a) {
    if (model.degree[a] < 0 || model.degree[a] > kMaxDegree) {
      std::ostringstream msg;
      msg << "afam: model degree " << model.degree[a] << " on axis " << kAxisName[a]
          << " is outside [0, " << kMaxDegree << "]";
      throw InvalidArgument(msg.str());
    }
  }
  validate(n, model.ncp, model.degree);
  const size_t mx = size_t(model.ncp[0]), my = size_t(model.ncp[1]), mz = size_t(model.ncp[2]);
  if (model.control.size() != mx * my * mz) {
    std::ostringstream msg;
    msg << "afam: model has " << model.control.size() << " control points, expected "
        << mx * my * mz;
    throw InvalidArgument(msg.str());
  }
  trimCache();
  const Axes axes{&axis(n[0], model.ncp[0], model.degree[0], false),
                  &axis(n[1], model.ncp[1], model.degree[1], false),
                  &axis(n[2], model.ncp[2], model.degree[2], false)};
  if (cpuHasAvx2())
    evaluatePassesAvx2(axes, model, n, samples, stats, gridOut);
  else
    evaluatePasses(axes, model, n, samples, stats, gridOut);
}

void BlockFitter::Impl::evaluatePasses(const Axes& axes, const FitResult& model,
                                       const std::array<int, 3>& n, const float* samples,
                                       ErrorStats* stats, float* gridOut) {
  const AxisSystem &ax = *axes.x, &ay = *axes.y, &az = *axes.z;
  const size_t nx = size_t(n[0]), ny = size_t(n[1]), nz = size_t(n[2]);
  const size_t mx = size_t(model.ncp[0]), my = size_t(model.ncp[1]), mz = size_t(model.ncp[2]);
  const size_t planeSize = nx * ny, block = planeSize * nz;

  // x: control lines -> sample lines, transposed (line index fastest) so that lines are the
  // vectors.
  const size_t lines = my * mz;
  grow(bufY, nx * lines, block);
  lineTiles(
      lines, mx, nx, model.control.data(),
      [&](size_t, size_t t, double* in, double* out) {
        evaluateRows(ax, in, t, out, t, t, nullptr);
      },
      bufY.data());
  // y: per z-slab, x-rows.
  grow(bufZ, planeSize * mz, block);
  for (size_t k = 0; k < mz; ++k)
    evaluateRows(ay, bufY.data() + k * nx * my, nx, bufZ.data() + k * planeSize, nx, nx, nullptr);
  // z: whole planes; either written out or reduced against the samples plane by plane.
  if (gridOut) {
    grow(plane, planeSize, 0);
    evaluateRows(az, bufZ.data(), planeSize, gridOut, planeSize, planeSize, plane.data());
    return;
  }
  const int w = az.p + 1;
  grow(plane, planeSize, 0);
  // Four lanes in one DoubleQuad (the reduction is vectorised); lane l takes the values c = l mod
  // 4, reduced in lane order at the end.
  const double inf = std::numeric_limits<double>::infinity();
  DoubleQuad sumSq = {0, 0, 0, 0}, maxErr = {0, 0, 0, 0};
  DoubleQuad lo = {inf, inf, inf, inf}, hi = {-inf, -inf, -inf, -inf};
  double tailSum = 0, tailMax = 0, tailLo = inf, tailHi = -inf;
  for (size_t i = 0; i < nz; ++i) {
    const double* wi = &az.weight[i * size_t(w)];
    const size_t f = size_t(az.first[i]);
    double* __restrict v = plane.data();
    const double* __restrict src0 = bufZ.data() + f * planeSize;
    // Degree 2 (three planes): each value summed where it is compared, not stored and read again;
    // other degrees a plane at a time. The same products and sums in the same order either way.
    const bool three = w == 3;
    if (!three) {
      const double a = wi[0];
      for (size_t c = 0; c < planeSize; ++c) v[c] = a * src0[c];
      for (int r = 1; r < w; ++r) {
        const double* __restrict src = bufZ.data() + (f + size_t(r)) * planeSize;
        const double b = wi[r];
        for (size_t c = 0; c < planeSize; ++c) v[c] += b * src[c];
      }
    }
    const double* __restrict src1 = three ? src0 + planeSize : src0;
    const double* __restrict src2 = three ? src1 + planeSize : src0;
    const double a0 = wi[0], a1 = three ? wi[1] : 0, a2 = three ? wi[2] : 0;
    const auto valueAt = [&](size_t c) {
      if (!three) return v[c];
      double value = a0 * src0[c];
      value += a1 * src1[c];
      return value + a2 * src2[c];
    };
    const float* __restrict sp = samples + i * planeSize;
    size_t c = 0;
    for (; c + 4 <= planeSize; c += 4) {
      DoubleQuad value;
      if (three) {
        DoubleQuad p0, p1, p2;
        std::memcpy(&p0, src0 + c, sizeof p0);
        std::memcpy(&p1, src1 + c, sizeof p1);
        std::memcpy(&p2, src2 + c, sizeof p2);
        value = a0 * p0;
        value += a1 * p1;
        value += a2 * p2;
      } else {
        std::memcpy(&value, v + c, sizeof value);
      }
      const DoubleQuad d = value - DoubleQuad{double(sp[c]), double(sp[c + 1]), double(sp[c + 2]),
                                              double(sp[c + 3])};
      sumSq += d * d;
      const DoubleQuad ad = d < 0 ? -d : d;
      maxErr = ad > maxErr ? ad : maxErr;
      lo = value < lo ? value : lo;
      hi = value > hi ? value : hi;
    }
    for (; c < planeSize; ++c) {
      const double value = valueAt(c);
      const double d = value - double(sp[c]);
      tailSum += d * d;
      tailMax = std::max(tailMax, std::fabs(d));
      tailLo = std::min(tailLo, value);
      tailHi = std::max(tailHi, value);
    }
  }
  double sum = tailSum, me = tailMax, mn = tailLo, mxv = tailHi;
  for (size_t l = 0; l < 4; ++l) {
    sum += sumSq[l];
    me = std::max(me, maxErr[l]);
    mn = std::min(mn, lo[l]);
    mxv = std::max(mxv, hi[l]);
  }
  const double count = double(nx * ny * nz);
  stats->rmse = std::sqrt(sum / count);
  stats->maxError = me;
  stats->minValue = mn;
  stats->maxValue = mxv;
}

ErrorStats BlockFitter::error(const float* samples, std::array<int, 3> n, const FitResult& model) {
  if (!samples) throw InvalidArgument("afam error: null sample pointer");
  Impl& im = *impl_;
  if (im.valid) {
    evaluateOnGrid(model, n, im.grid);
    return errorOnValid(im.grid.data(), samples, im.grid.size(), im.valid->data());
  }
  ErrorStats stats;
  im.evaluate(model, n, samples, &stats, nullptr);
  return stats;
}

void BlockFitter::setMask(const std::vector<uint32_t>* valid) { impl_->valid = valid; }

namespace {

AFAM_TARGET_AVX2 ErrorStats errorOnValidAvx2(const float* model, const float* samples, size_t count,
                                             const uint32_t* valid) {
  return errorOnValidOf([model](size_t i) { return model[i]; }, samples, count, valid);
}

}  // namespace

ErrorStats errorOnValid(const float* model, const float* samples, size_t count,
                        const uint32_t* valid) {
  if (cpuHasAvx2()) return errorOnValidAvx2(model, samples, count, valid);
  return errorOnValidOf([model](size_t i) { return model[i]; }, samples, count, valid);
}

void BlockFitter::evaluateOnGrid(const FitResult& model, std::array<int, 3> n,
                                 std::vector<float>& out) {
  validateSamples(n);
  out.resize(size_t(n[0]) * size_t(n[1]) * size_t(n[2]));
  impl_->evaluate(model, n, nullptr, nullptr, out.data());
}

BlockFitter& threadFitter() {
  thread_local BlockFitter fitter;
  return fitter;
}

void evaluateOnGrid(const FitResult& model, std::array<int, 3> n, std::vector<float>& out) {
  threadFitter().evaluateOnGrid(model, n, out);
}

std::vector<double> collocationMatrix(int n, int ncp, int degree) {
  if (n < 1) throw InvalidArgument("afam collocation: n must be >= 1");
  if (degree < 1 || degree > kMaxDegree)
    throw InvalidArgument("afam collocation: degree must be in [1, 5]");
  const int p = effectiveDegree(degree, n);
  if (ncp < p + 1 || ncp > n) {
    std::ostringstream msg;
    msg << "afam collocation: NCP " << ncp << " outside [" << p + 1 << ", " << n << "]";
    throw InvalidArgument(msg.str());
  }
  AxisSystem s;
  buildCollocation(s, n, ncp, p);
  std::vector<double> a(size_t(n) * size_t(ncp), 0.0);
  for (int i = 0; i < n; ++i)
    for (int r = 0; r <= p; ++r)
      a[size_t(i) * size_t(ncp) + size_t(s.first[size_t(i)] + r)] =
          s.weight[size_t(i) * size_t(p + 1) + size_t(r)];
  return a;
}

AxisConditioning axisConditioning(int n, int ncp, int degree) {
  const std::vector<double> values = collocationMatrix(n, ncp, degree);
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> a(
      values.data(), n, ncp);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(a);  // singular values only
  const auto& sv = svd.singularValues();
  AxisConditioning out;
  const double smax = sv(0), smin = sv(sv.size() - 1);
  out.collocation = smin > 0 ? smax / smin : std::numeric_limits<double>::infinity();
  out.normal = out.collocation * out.collocation;
  return out;
}

}  // namespace afam
