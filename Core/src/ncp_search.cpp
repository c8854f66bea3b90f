// SPDX-License-Identifier: BSD-3-Clause
#include "afam/ncp_search.hpp"

#include <algorithm>
#include <limits>
#include <vector>

#include "afam/fit.hpp"

namespace afam {

int searchNcp(BlockFitter& fitter, const float* samples, Int3 n, int degree, double bound, SearchMethod method,
              int window, FitResult& result, int64_t& fits) {
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
    const bool ok = fitter.fitWithin(samples, n, clampNcp(k, n, degs), degree, bound, squares, tmp);
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
  const size_t sx = 1, sy = size_t(n[0]), sz = size_t(n[0]) * size_t(n[1]);
  const size_t stride[3] = {sx, sy, sz};
  for (int a = 0; a < 3; ++a) {
    if (n[a] < 3) continue;
    double sum = 0;
    int64_t count = 0;
    for (int z = 0; z < n[2]; ++z)
      for (int y = 0; y < n[1]; ++y)
        for (int x = 0; x < n[0]; ++x) {
          const int c[3] = {x, y, z};
          if (c[a] == 0 || c[a] == n[a] - 1) continue;
          const size_t i = size_t(z) * sz + size_t(y) * sy + size_t(x);
          const double d = double(samples[i - stride[a]]) - 2.0 * double(samples[i]) + double(samples[i + stride[a]]);
          sum += d * d;
          ++count;
        }
    r[size_t(a)] = count ? sum / double(count) : 0;
  }
  return r;
}

bool refineNcpPerAxis(BlockFitter& fitter, const float* samples, Int3 n, int degree, double bound,
                      FitResult& result, int64_t& fits) {
  const std::array<double, 3> rough = axisRoughness(samples, n);
  const double roughest = *std::max_element(rough.begin(), rough.end());
  if (!(roughest > 0)) return false;
  std::array<int, 3> order{0, 1, 2};
  std::sort(order.begin(), order.end(), [&](int a, int b) { return rough[size_t(a)] < rough[size_t(b)]; });
  FitResult trial;
  bool reduced = false;
  double squares = -1;  // computed for the first axis tried
  for (int a : order) {
    if (rough[size_t(a)] * kAnisotropy > roughest) continue;
    if (squares < 0) squares = sumOfSquares(samples, n);
    const int lo = effectiveDegree(degree, n[size_t(a)]) + 1;
    int fail = lo - 1, pass = result.ncp[size_t(a)];  // NCP `pass` meets the bound on this axis
    while (pass - fail > 1) {
      const int mid = fail == lo - 1 ? lo : fail + (pass - fail) / 2;  // try p+1 first: layers need no more
      Int3 ncp = result.ncp;
      ncp[size_t(a)] = mid;
      const bool ok = fitter.fitWithin(samples, n, ncp, degree, bound, squares, trial);
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
