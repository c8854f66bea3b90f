// SPDX-License-Identifier: BSD-3-Clause
#include "afam/encode/ncp_search.hpp"

#include <algorithm>
#include <limits>
#include <vector>

#include "afam/spline/fit.hpp"

namespace afam {

namespace {

/// Whether the fit at `ncp` keeps the bound: fitWithin's answer for an RMSE; for a pointwise
/// bound, an RMSE above it already fails (no sample can be within it then), else every sample's
/// error is measured.
bool fitKeeps(BlockFitter& fitter, const float* samples, Int3 n, Int3 ncp, int degree, double bound,
              BoundKind kind, double squares, FitResult& out) {
  if (!fitter.fitWithin(samples, n, ncp, degree, bound, squares, out)) return false;
  if (kind == BoundKind::Rmse) return true;
  fitter.measure(samples, n, out);
  return out.error.maxError <= bound;
}

}  // namespace

int searchNcp(BlockFitter& fitter, const float* samples, Int3 n, int degree, double bound,
              SearchMethod method, int window, FitResult& result, int64_t& fits, BoundKind kind) {
  Int3 degs{};
  int nmax = 1;
  for (int a = 0; a < 3; ++a) {
    degs[a] = effectiveDegree(degree, n[a]);
    nmax = std::max(nmax, n[a]);
  }
  const int lo = std::min(degree + 1, nmax), hi = nmax;
  FitResult tmp, best, top;
  int bestK = std::numeric_limits<int>::max();
  bool haveTop = false;
  std::vector<signed char> state(size_t(hi) + 1, -1);  // -1 unknown, 0 fails, 1 passes
  const double squares = sumOfSquares(samples, n);
  auto pass = [&](int k) -> bool {
    if (state[size_t(k)] >= 0) return state[size_t(k)] == 1;
    const bool ok =
        fitKeeps(fitter, samples, n, clampNcp(k, n, degs), degree, bound, kind, squares, tmp);
    ++fits;
    state[size_t(k)] = ok ? 1 : 0;
    if (ok && k < bestK) {
      bestK = k;
      std::swap(best, tmp);
    } else if (k == hi) {
      std::swap(top, tmp);
      haveTop = true;
    }
    return ok;
  };
  auto finish = [&]() {
    int k = bestK;
    if (bestK <= hi) {
      result = std::move(best);
    } else {
      if (!haveTop) pass(hi);
      result = std::move(top);
      k = hi;
    }
    fitter.measure(samples, n, result);
    return k;
  };
  if (method == SearchMethod::Exhaustive || hi - lo < 2) {
    for (int k = lo; k <= hi; ++k) pass(k);
    return finish();
  }
  if (pass(lo)) return finish();
  if (!pass(hi)) {
    for (int k = lo + 1; k < hi; ++k)
      if (pass(k)) break;
    return finish();
  }
  int a = lo, b = hi;  // a fails, b passes
  while (b - a > 1) {
    const int m = a + (b - a) / 2;
    if (pass(m))
      b = m;
    else
      a = m;
  }
  // Local check below the boundary: a non-monotone error curve may pass again just below it.
  int stop = std::max(lo + 1, b - 1 - window);
  for (int j = b - 2; j >= stop; --j)
    if (pass(j)) stop = std::max(lo + 1, j - 1 - window);
  return finish();
}

std::array<double, 3> axisRoughness(const float* samples, Int3 n) {
  std::array<double, 3> r{0, 0, 0};
  const size_t nx = size_t(n[0]), ny = size_t(n[1]), nz = size_t(n[2]);
  const size_t stride[3] = {1, nx, nx * ny};
  std::vector<double> column(
      nx);  // a sum per x: the inner loop is independent across x (vectorised)
  for (int a = 0; a < 3; ++a) {
    if (n[a] < 3) continue;
    std::fill(column.begin(), column.end(), 0.0);
    const size_t s = stride[a], x0 = a == 0 ? 1 : 0, x1 = a == 0 ? nx - 1 : nx;
    for (size_t z = a == 2 ? 1 : 0; z < (a == 2 ? nz - 1 : nz); ++z)
      for (size_t y = a == 1 ? 1 : 0; y < (a == 1 ? ny - 1 : ny); ++y) {
        const float* row = samples + z * stride[2] + y * nx;
        const float *prev = row - s, *next = row + s;
        for (size_t x = x0; x < x1; ++x) {
          const double d = double(prev[x]) - 2.0 * double(row[x]) + double(next[x]);
          column[x] += d * d;
        }
      }
    double sum = 0;
    for (double v : column) sum += v;
    Int3 interior = n;
    interior[size_t(a)] -= 2;
    r[size_t(a)] = sum / (double(interior[0]) * double(interior[1]) * double(interior[2]));
  }
  return r;
}

bool refineNcpPerAxis(BlockFitter& fitter, const float* samples, Int3 n, int degree, double bound,
                      FitResult& result, int64_t& fits, BoundKind kind) {
  const std::array<double, 3> rough = axisRoughness(samples, n);
  const double roughest = *std::max_element(rough.begin(), rough.end());
  if (!(roughest > 0)) {
    fitter.measure(samples, n, result);
    return false;
  }
  std::array<int, 3> order{0, 1, 2};
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return rough[size_t(a)] < rough[size_t(b)]; });
  FitResult trial;
  bool reduced = false;
  double squares = -1;  // computed for the first axis tried
  for (int a : order) {
    if (rough[size_t(a)] * kAnisotropy > roughest) continue;
    if (squares < 0) squares = sumOfSquares(samples, n);
    const int lo = effectiveDegree(degree, n[size_t(a)]) + 1;
    int fail = lo - 1, pass = result.ncp[size_t(a)];  // NCP `pass` meets the bound on this axis
    while (pass - fail > 1) {
      const int mid =
          fail == lo - 1 ? lo : fail + (pass - fail) / 2;  // try p+1 first: layers need no more
      Int3 ncp = result.ncp;
      ncp[size_t(a)] = mid;
      const bool ok = fitKeeps(fitter, samples, n, ncp, degree, bound, kind, squares, trial);
      ++fits;
      if (ok) {
        pass = mid;
        std::swap(result, trial);
        reduced = true;
      } else {
        fail = mid;
      }
    }
  }
  fitter.measure(samples, n, result);
  return reduced;
}

}  // namespace afam
