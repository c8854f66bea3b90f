// SPDX-License-Identifier: BSD-3-Clause
#include "afam/search/ncp_search.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Dense>

#include "afam/base/cpu_features.hpp"
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

/// The verdicts to use for a search at `bound`: none unless they were given for it.
const NcpVerdicts* verdictsAt(const NcpVerdicts* verdicts, double bound, BoundKind kind) {
  return verdicts && kind == BoundKind::Rmse && verdicts->bound == bound ? verdicts : nullptr;
}

Int3 degreesOf(int degree, Int3 n) {
  Int3 degs{};
  for (int a = 0; a < 3; ++a) degs[a] = effectiveDegree(degree, n[a]);
  return degs;
}

}  // namespace

Verdict NcpVerdicts::of(Int3 ncp) const {
  for (const auto& [at, verdict] : known)
    if (at == ncp) return verdict;
  return Verdict::Unknown;
}

void NcpVerdicts::set(Int3 ncp, Verdict verdict) {
  for (auto& [at, v] : known)
    if (at == ncp) {
      v = verdict;
      return;
    }
  known.emplace_back(ncp, verdict);
}

int smallestPassingNcp(int lo, int hi, SearchMethod method, int window,
                       const std::function<bool(int)>& pass) {
  std::vector<signed char> state(size_t(hi) + 1, -1);  // -1 unknown, 0 fails, 1 passes
  int best = hi + 1;
  auto ask = [&](int k) {
    if (state[size_t(k)] < 0) state[size_t(k)] = pass(k) ? 1 : 0;
    if (state[size_t(k)] == 1) best = std::min(best, k);
    return state[size_t(k)] == 1;
  };
  if (method == SearchMethod::Exhaustive || hi - lo < 2) {
    for (int k = lo; k <= hi; ++k) ask(k);
    return best;
  }
  if (ask(lo)) return best;
  if (!ask(hi)) {
    for (int k = lo + 1; k < hi; ++k)
      if (ask(k)) break;
    return best;
  }
  int a = lo, b = hi;  // a fails, b passes
  while (b - a > 1) {
    const int m = a + (b - a) / 2;
    if (ask(m))
      b = m;
    else
      a = m;
  }
  // Local check below the boundary: a non-monotone error curve may pass again just below it.
  int stop = std::max(lo + 1, b - 1 - window);
  for (int j = b - 2; j >= stop; --j)
    if (ask(j)) stop = std::max(lo + 1, j - 1 - window);
  return best;
}

int searchNcp(BlockFitter& fitter, const float* samples, Int3 n, int degree, double bound,
              SearchMethod method, int window, FitResult& result, int64_t& fits, BoundKind kind,
              const NcpVerdicts* given) {
  const NcpVerdicts* verdicts = verdictsAt(given, bound, kind);
  const Int3 degs = degreesOf(degree, n);
  const int nmax = std::max({1, n[0], n[1], n[2]});
  const int lo = std::min(degree + 1, nmax), hi = nmax;
  const double squares = sumOfSquares(samples, n);
  FitResult tmp, best, top;  // top: the fit at n when it fails
  int fitted = -1;           // the NCP `best` holds: the smallest passing one fitted
  bool haveTop = false;
  auto fitAt = [&](int k) {
    ++fits;
    return fitKeeps(fitter, samples, n, clampNcp(k, n, degs), degree, bound, kind, squares, tmp);
  };
  auto pass = [&](int k) {
    const Verdict v = verdicts ? verdicts->of(clampNcp(k, n, degs)) : Verdict::Unknown;
    if (v != Verdict::Unknown) return v == Verdict::Passes;
    const bool ok = fitAt(k);
    if (ok && (fitted < 0 || k < fitted)) {
      std::swap(best, tmp);
      fitted = k;
    } else if (!ok && k == hi) {
      std::swap(top, tmp);
      haveTop = true;
    }
    return ok;
  };
  const int found = smallestPassingNcp(lo, hi, method, window, pass);
  if (found <= hi && fitted == found) {
    result = std::move(best);
  } else if (found > hi && haveTop) {
    result = std::move(top);
  } else {  // a verdict's NCP, or n: fit it
    const bool ok = fitAt(std::min(found, hi));
    if (!ok && found <= hi)  // a verdict said it passes, the fit says not: search by fitting
      return searchNcp(fitter, samples, n, degree, bound, method, window, result, fits, kind);
    result = std::move(tmp);
  }
  fitter.measure(samples, n, result);
  return std::min(found, hi);
}

namespace {

/// The square of a second difference a - 2b + c, taken in D (double; or float where the samples
/// are small integers, where it is exact) and returned as a double: the same value either way.
template <typename D>
__attribute__((always_inline)) inline double squaredSecondDifference(float a, float b, float c) {
  const D d = D(a) - D(2) * D(b) + D(c);
  return double(d * d);
}

/// axisRoughness's sums in one pass over the block's rows (each row with its neighbours along y
/// and z, in cache once), compiled also for AVX2 (no FMA) and chosen at run time. An axis' sum per
/// x gathers its rows in increasing (z, y), the order of a pass of its own, and the columns are
/// added in increasing x: the same sums as three passes. D: the differences' type (above).
template <typename D>
__attribute__((always_inline)) inline std::array<double, 3> axisRoughnessBody(const float* samples,
                                                                              Int3 n) {
  const size_t nx = size_t(n[0]), ny = size_t(n[1]), nz = size_t(n[2]);
  thread_local std::vector<double> columns;  // a sum per x and axis (vectorised across x)
  columns.assign(3 * nx, 0.0);
  double* __restrict cx = columns.data();
  double* __restrict cy = cx + nx;
  double* __restrict cz = cy + nx;
  const size_t plane = nx * ny;
  for (size_t z = 0; z < nz; ++z)
    for (size_t y = 0; y < ny; ++y) {
      const float* row = samples + z * plane + y * nx;
      if (nx >= 3)
        for (size_t x = 1; x + 1 < nx; ++x)
          cx[x] += squaredSecondDifference<D>(row[x - 1], row[x], row[x + 1]);
      if (ny >= 3 && y >= 1 && y + 1 < ny) {
        const float* below = row - nx;  // in the block: y >= 1
        const float* above = row + nx;
        for (size_t x = 0; x < nx; ++x)
          cy[x] += squaredSecondDifference<D>(below[x], row[x], above[x]);
      }
      if (nz >= 3 && z >= 1 && z + 1 < nz) {
        const float* below = row - plane;  // in the block: z >= 1
        const float* above = row + plane;
        for (size_t x = 0; x < nx; ++x)
          cz[x] += squaredSecondDifference<D>(below[x], row[x], above[x]);
      }
    }
  std::array<double, 3> r{0, 0, 0};
  for (int a = 0; a < 3; ++a) {
    if (n[a] < 3) continue;
    double sum = 0;
    for (size_t x = 0; x < nx; ++x) sum += columns[size_t(a) * nx + x];
    Int3 interior = n;
    interior[size_t(a)] -= 2;
    r[size_t(a)] = sum / (double(interior[0]) * double(interior[1]) * double(interior[2]));
  }
  return r;
}

template <typename D>
AFAM_TARGET_AVX2 std::array<double, 3> axisRoughnessAvx2(const float* samples, Int3 n) {
  return axisRoughnessBody<D>(samples, n);
}

}  // namespace

std::array<double, 3> axisRoughness(const float* samples, Int3 n, bool smallIntegers) {
  if (smallIntegers)
    return cpuHasAvx2() ? axisRoughnessAvx2<float>(samples, n)
                        : axisRoughnessBody<float>(samples, n);
  return cpuHasAvx2() ? axisRoughnessAvx2<double>(samples, n)
                      : axisRoughnessBody<double>(samples, n);
}

namespace {

/// An orthonormal basis of the polynomials of degree <= p on the points 0..n-1 (Gram-Schmidt in
/// double), p + 1 columns of n values; fewer when n <= p.
std::vector<std::vector<double>> polynomialBasis(int n, int p) {
  std::vector<std::vector<double>> q;
  for (int d = 0; d <= p && d < n; ++d) {
    std::vector<double> v(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) v[size_t(i)] = std::pow(double(i) / double(std::max(1, n - 1)), d);
    for (int pass = 0; pass < 2; ++pass)  // twice: orthogonal to rounding
      for (const std::vector<double>& b : q) {
        double dot = 0;
        for (int i = 0; i < n; ++i) dot += v[size_t(i)] * b[size_t(i)];
        for (int i = 0; i < n; ++i) v[size_t(i)] -= dot * b[size_t(i)];
      }
    double norm = 0;
    for (double x : v) norm += x * x;
    norm = std::sqrt(norm);
    for (double& x : v) x /= norm;
    q.push_back(std::move(v));
  }
  return q;
}

}  // namespace

double fewestPointsRmseFloor(const float* samples, Int3 n, int degree, int stride,
                             double* squares) {
  const int nx = n[0];
  const std::vector<std::vector<double>> q = polynomialBasis(nx, effectiveDegree(degree, nx));
  std::vector<double> r(static_cast<size_t>(nx));
  double residual = 0;
  for (int z = 0; z < n[2]; z += stride)
    for (int y = 0; y < n[1]; y += stride) {
      const float* line = samples + (size_t(z) * size_t(n[1]) + size_t(y)) * size_t(nx);
      for (int i = 0; i < nx; ++i) r[size_t(i)] = double(line[i]);
      if (squares) *squares += sumOfSquares(line, {nx, 1, 1});
      for (const std::vector<double>& b : q) {  // r minus its projection, one column at a time
        double dot = 0;
        for (int i = 0; i < nx; ++i) dot += r[size_t(i)] * b[size_t(i)];
        for (int i = 0; i < nx; ++i) r[size_t(i)] -= dot * b[size_t(i)];
      }
      for (double v : r) residual += v * v;
    }
  return std::sqrt(residual / (double(n[0]) * double(n[1]) * double(n[2])));
}

bool fewestPointsFail(const float* samples, Int3 n, int degree, double bound,
                      NcpVerdicts& verdicts) {
  double squares = 0;  // of the lines the floor read: their scale, for the rounding's margin
  const double floor = fewestPointsRmseFloor(samples, n, degree, 4, &squares);
  const double scale = std::sqrt(squares / (double(n[0]) * double(n[1]) * double(n[2])));
  if (!(floor > bound * (1 + 1e-6) + 1e-9 * scale)) return false;  // clear of the rounding
  if (verdicts.bound != bound) verdicts = NcpVerdicts{bound, {}};
  const int nmax = std::max({1, n[0], n[1], n[2]});
  const Int3 fewest = clampNcp(std::min(degree + 1, nmax), n, degreesOf(degree, n));
  if (verdicts.of(fewest) != Verdict::Unknown) return false;  // one given ahead stands
  verdicts.set(fewest, Verdict::Fails);
  return true;
}

double interpolationGain(int n, int degree) {
  thread_local std::vector<std::pair<std::pair<int, int>, double>> known;
  const std::pair<int, int> key{n, effectiveDegree(degree, n)};
  for (const auto& [at, gain] : known)
    if (at == key) return gain;
  const std::vector<double> a = collocationMatrix(n, n, degree);
  const Eigen::MatrixXd inverse =
      Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
          a.data(), n, n)
          .fullPivLu()
          .inverse();
  const double gain = inverse.cwiseAbs().rowwise().sum().maxCoeff();
  known.emplace_back(key, gain);
  return gain;
}

bool interpolantPasses(const float* samples, Int3 n, int degree, double bound,
                       NcpVerdicts& verdicts) {
  double gain = 1;
  for (int a = 0; a < 3; ++a) gain *= interpolationGain(n[a], degree);
  const size_t count = size_t(n[0]) * size_t(n[1]) * size_t(n[2]);
  const float largest = largestMagnitude(samples, count);
  // float32 rounding of the points (2^-24 relative) and the double solve's error (1e-9 of them:
  // ~1e-13 at a condition number of 100), twice over.
  const double worst = 2 * (std::ldexp(1.0, -24) + 1e-9) * gain * double(largest);
  if (!(worst <= bound) || !(gain < 1e6)) return false;
  if (verdicts.bound != bound) verdicts = NcpVerdicts{bound, {}};
  if (verdicts.of(n) != Verdict::Unknown) return false;  // one given ahead stands
  verdicts.set(n, Verdict::Passes);
  return true;
}

Int3 fewerPointsPerAxis(const std::array<double, 3>& rough, Int3 start, Int3 n, int degree,
                        const std::function<bool(Int3)>& pass) {
  const double roughest = *std::max_element(rough.begin(), rough.end());
  if (!(roughest > 0)) return start;
  std::array<int, 3> order{0, 1, 2};
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return rough[size_t(a)] < rough[size_t(b)]; });
  Int3 ncp = start;
  for (int a : order) {
    if (rough[size_t(a)] * kAnisotropy > roughest) continue;
    const int lo = effectiveDegree(degree, n[size_t(a)]) + 1;
    int fail = lo - 1, passing = ncp[size_t(a)];  // NCP `passing` meets the bound on this axis
    while (passing - fail > 1) {
      const int mid =
          fail == lo - 1 ? lo : fail + (passing - fail) / 2;  // try p+1 first: layers need no more
      Int3 trial = ncp;
      trial[size_t(a)] = mid;
      if (pass(trial)) {
        passing = mid;
        ncp = trial;
      } else {
        fail = mid;
      }
    }
  }
  return ncp;
}

bool refineNcpPerAxis(BlockFitter& fitter, const float* samples, Int3 n, int degree, double bound,
                      FitResult& result, int64_t& fits, BoundKind kind, const NcpVerdicts* given,
                      const std::array<double, 3>* roughness) {
  const NcpVerdicts* verdicts = verdictsAt(given, bound, kind);
  const std::array<double, 3> rough = roughness ? *roughness : axisRoughness(samples, n);
  const Int3 start = result.ncp;
  FitResult trial, entry;
  if (verdicts) entry = result;  // to refine again by fitting should a verdict be wrong
  double squares = -1;           // computed for the first fit
  auto fitAt = [&](Int3 ncp) {
    if (squares < 0) squares = sumOfSquares(samples, n);
    ++fits;
    return fitKeeps(fitter, samples, n, ncp, degree, bound, kind, squares, trial);
  };
  auto pass = [&](Int3 ncp) {
    const Verdict v = verdicts ? verdicts->of(ncp) : Verdict::Unknown;
    if (v != Verdict::Unknown) return v == Verdict::Passes;
    const bool ok = fitAt(ncp);
    if (ok) std::swap(result, trial);
    return ok;
  };
  const Int3 ncp = fewerPointsPerAxis(rough, start, n, degree, pass);
  if (result.ncp != ncp) {  // a verdict's NCP: fit it
    if (!fitAt(ncp)) {
      result = std::move(entry);
      return refineNcpPerAxis(fitter, samples, n, degree, bound, result, fits, kind, nullptr,
                              &rough);
    }
    std::swap(result, trial);
  }
  fitter.measure(samples, n, result);
  return ncp != start;
}

}  // namespace afam
