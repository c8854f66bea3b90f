// SPDX-License-Identifier: BSD-3-Clause
// Per-axis NCP: the refinement keeps the bound, never adds control points, gives the degree's
// minimum to axes along which the block is a polynomial of that degree, leaves isotropic blocks
// alone, and against an exhaustive search over every (ncp_x, ncp_y, ncp_z) on small blocks it is
// within 25% of the smallest passing product (equal on the blocks tested).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "afam/encode/encoder.hpp"
#include "afam/encode/model_sink.hpp"
#include "afam/search/ncp_search.hpp"
#include "afam/spline/fit.hpp"

using namespace afam;

namespace {

constexpr double kPi = 3.14159265358979323846;

/// n^3 samples of f(x, y, z) on [0, 1]^3.
template <typename F>
std::vector<float> sampled(int n, F f) {
  std::vector<float> v(size_t(n) * size_t(n) * size_t(n));
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
        v[(size_t(z) * size_t(n) + size_t(y)) * size_t(n) + size_t(x)] =
            float(f(double(x) / (n - 1), double(y) / (n - 1), double(z) / (n - 1)));
  return v;
}

int64_t product(const Int3& ncp) { return int64_t(ncp[0]) * ncp[1] * ncp[2]; }

/// Layers along z on a quadratic trend in x: the spline's degree 2 represents x and y exactly.
double layered(double x, double y, double z) {
  return std::sin(7 * kPi * z) + 0.3 * x * x + 0.0 * y;
}

}  // namespace

TEST(NcpSearch, RoughnessSeesTheLayeredAxis) {
  const int n = 33;
  const std::vector<float> v = sampled(n, layered);
  const std::array<double, 3> r = axisRoughness(v.data(), {n, n, n});
  EXPECT_EQ(r[1], 0.0);
  EXPECT_GT(r[2], 1000 * r[0]);
  EXPECT_GT(r[0], 0.0);
}

namespace {

/// axisRoughness as three passes, an axis at a time (its first form): along each axis the sum per
/// x over the rows in increasing (z, y), then over x.
std::array<double, 3> roughnessAxisByAxis(const std::vector<float>& v, Int3 n) {
  std::array<double, 3> r{0, 0, 0};
  const size_t nx = size_t(n[0]), ny = size_t(n[1]), nz = size_t(n[2]);
  const size_t stride[3] = {1, nx, nx * ny};
  for (int a = 0; a < 3; ++a) {
    if (n[a] < 3) continue;
    std::vector<double> column(nx, 0.0);
    for (size_t z = a == 2 ? 1 : 0; z < (a == 2 ? nz - 1 : nz); ++z)
      for (size_t y = a == 1 ? 1 : 0; y < (a == 1 ? ny - 1 : ny); ++y)
        for (size_t x = a == 0 ? 1 : 0; x < (a == 0 ? nx - 1 : nx); ++x) {
          const size_t i = z * stride[2] + y * nx + x, s = stride[a];
          const double d = double(v[i - s]) - 2.0 * double(v[i]) + double(v[i + s]);
          column[x] += d * d;
        }
    double sum = 0;
    for (double c : column) sum += c;
    Int3 interior = n;
    interior[size_t(a)] -= 2;
    r[size_t(a)] = sum / (double(interior[0]) * double(interior[1]) * double(interior[2]));
  }
  return r;
}

}  // namespace

TEST(NcpSearch, RoughnessInOnePassIsTheSumsOfAPassAnAxis) {
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(100.0f, 30.0f);
  const std::vector<Int3> shapes{{53, 53, 53}, {2, 40, 33}, {40, 1, 5},
                                 {7, 3, 64},   {3, 3, 3},   {65, 64, 2}};
  for (const Int3& n : shapes) {
    std::vector<float> v(static_cast<size_t>(n[0]) * size_t(n[1]) * size_t(n[2]));
    for (float& x : v) x = noise(rng);
    const std::array<double, 3> got = axisRoughness(v.data(), n), want = roughnessAxisByAxis(v, n);
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(got[size_t(a)], want[size_t(a)])
          << n[0] << "x" << n[1] << "x" << n[2] << " axis " << a;
      EXPECT_EQ(got[size_t(a)] > 0, n[a] >= 3);
    }
  }
}

TEST(NcpSearch, RoughnessOfSmallIntegersInFloatIsTheSameDoubles) {
  std::mt19937 rng(11);
  const std::vector<Int3> shapes{{66, 66, 66}, {65, 64, 3}, {2, 40, 33}, {17, 1, 9}, {9, 13, 2}};
  for (const Int3& n : shapes) {
    const size_t count = static_cast<size_t>(n[0]) * size_t(n[1]) * size_t(n[2]);
    // Bytes as uint8 and int8 hold them, and the extremes: 0 and 255 alternating (|d| = 1020).
    for (int pattern = 0; pattern < 3; ++pattern) {
      std::vector<float> v(count);
      for (size_t i = 0; i < count; ++i)
        v[i] = pattern == 0   ? float(rng() % 256)
               : pattern == 1 ? float(int(rng() % 256) - 128)
                              : float(((i + i / size_t(n[0]) + i / size_t(n[0] * n[1])) % 2) * 255);
      const std::array<double, 3> fast = axisRoughness(v.data(), n, true),
                                  want = roughnessAxisByAxis(v, n);
      for (int a = 0; a < 3; ++a)
        EXPECT_EQ(fast[size_t(a)], want[size_t(a)])
            << n[0] << "x" << n[1] << "x" << n[2] << " pattern " << pattern << " axis " << a;
    }
  }
}

TEST(NcpSearch, LayeredBlockKeepsTheBoundWithFarFewerControlPoints) {
  const int n = 33;
  const Int3 dims{n, n, n};
  const std::vector<float> v = sampled(n, layered);
  BlockFitter fitter;
  for (double bound : {1e-2, 1e-3, 1e-4}) {
    SCOPED_TRACE(bound);
    FitResult fr;
    int64_t fits = 0;
    const int k = searchNcp(fitter, v.data(), dims, 2, bound, SearchMethod::Fast, 3, fr, fits);
    ASSERT_LE(fr.error.rmse, bound);
    ASSERT_GT(k, 3);
    const Int3 iso = fr.ncp;
    ASSERT_TRUE(refineNcpPerAxis(fitter, v.data(), dims, 2, bound, fr, fits));
    EXPECT_LE(fr.error.rmse, bound);
    EXPECT_EQ(fr.ncp[0], 3);  // quadratic along x
    EXPECT_EQ(fr.ncp[1], 3);  // constant along y
    EXPECT_LE(fr.ncp[2], iso[2]);
    EXPECT_LE(product(fr.ncp) * 9, product(iso)) << k;
    // The refined model is what the fitter gives at those counts, and its error is measured.
    const FitResult again = fitter.fit(v.data(), dims, fr.ncp, 2);
    EXPECT_NEAR(again.error.rmse, fr.error.rmse, 1e-12 + 1e-9 * fr.error.rmse);
  }
}

TEST(NcpSearch, IsotropicBlockIsLeftAlone) {
  const int n = 33;
  const std::vector<float> v = sampled(n, [](double x, double y, double z) {
    return std::cos(5 * kPi *
                    std::sqrt((x - .4) * (x - .4) + (y - .5) * (y - .5) + (z - .6) * (z - .6)));
  });
  BlockFitter fitter;
  FitResult fr;
  int64_t fits = 0;
  searchNcp(fitter, v.data(), {n, n, n}, 2, 1e-3, SearchMethod::Fast, 3, fr, fits);
  const Int3 iso = fr.ncp;
  const int64_t before = fits;
  EXPECT_FALSE(refineNcpPerAxis(fitter, v.data(), {n, n, n}, 2, 1e-3, fr, fits));
  EXPECT_EQ(fr.ncp, iso);
  EXPECT_EQ(fits, before);  // no fit spent where no axis is smoother
}

TEST(NcpSearch, WithinAQuarterOfTheExhaustiveSmallestProductOnAnisotropicBlocks) {
  // Every (kx, ky, kz) in [3, 13]^3 on 13^3 blocks: the smallest product that meets the bound.
  const int n = 13;
  const Int3 dims{n, n, n};
  BlockFitter fitter;
  struct Case {
    const char* name;
    double (*f)(double, double, double);
  };
  const Case cases[] = {
      {"layers", [](double x, double, double z) { return std::sin(3 * kPi * z) + 0.2 * x * x; }},
      {"sheet",
       [](double x, double y, double z) {
         return std::exp(-40 * (z - 0.5) * (z - 0.5)) * (1 + 0.2 * x + 0.1 * y);
       }},
      {"ramp-and-wave",
       [](double x, double y, double) { return std::cos(2.5 * kPi * y) * (1 + x); }},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const std::vector<float> v = sampled(n, c.f);
    const double bound = 1e-3;
    int64_t best = product({n, n, n});
    for (int kz = 3; kz <= n; ++kz)
      for (int ky = 3; ky <= n; ++ky)
        for (int kx = 3; kx <= n; ++kx)
          if (int64_t(kx) * ky * kz < best &&
              fitter.fit(v.data(), dims, {kx, ky, kz}, 2).error.rmse <= bound)
            best = int64_t(kx) * ky * kz;
    FitResult fr;
    int64_t fits = 0;
    searchNcp(fitter, v.data(), dims, 2, bound, SearchMethod::Fast, 3, fr, fits);
    const int64_t iso = product(fr.ncp);
    refineNcpPerAxis(fitter, v.data(), dims, 2, bound, fr, fits);
    std::printf(
        "%s: isotropic %lld, per-axis %lld (%d x %d x %d), exhaustive smallest %lld, fits %lld\n",
        c.name, (long long)iso, (long long)product(fr.ncp), fr.ncp[0], fr.ncp[1], fr.ncp[2],
        (long long)best, (long long)fits);
    EXPECT_LE(fr.error.rmse, bound);
    EXPECT_LE(double(product(fr.ncp)), 1.25 * double(best));
    EXPECT_LT(product(fr.ncp), iso);
  }
}

TEST(NcpSearch, EncodeOfALayeredVolumeIsSmallerAndMeetsTheBound) {
  const int n = 65;
  const std::vector<float> v = sampled(n, [](double x, double y, double z) {
    return std::sin(9 * kPi * z) * (1 + 0.1 * x) + 0.05 * y;
  });
  std::array<uint64_t, 2> bytes{};
  for (int perAxis = 0; perAxis < 2; ++perAxis) {
    EncoderOptions opt;
    opt.errorBound = 1e-3;
    opt.relativeBound = true;
    opt.levels = 2;
    opt.blocksPerAxis = 2;
    opt.threads = 2;
    opt.perAxisNcp = perAxis == 1;
    ArraySource src(v.data(), {n, n, n});
    InMemoryModels models;
    const EncodeStats s = encodeVolume(src, opt, models);
    EXPECT_LE(s.maxRmse, s.bound);
    for (const ModelEntry& e : models.entries) EXPECT_LE(e.rmse, s.bound);
    bytes[size_t(perAxis)] = s.bytesOut;
  }
  std::printf("layered 65^3 at 1e-3: isotropic %llu bytes, per-axis %llu bytes\n",
              (unsigned long long)bytes[0], (unsigned long long)bytes[1]);
  EXPECT_LT(double(bytes[1]), 0.8 * double(bytes[0]));
}

TEST(NcpSearch, TheFewestPointsFloorLiesUnderEveryFitOfTheFewestPoints) {
  // fewestPointsRmseFloor is under the RMSE of the least-squares fit at p + 1 (the smallest error
  // any model of that NCP has) on smooth, rough and noisy blocks of odd shapes, every degree; and
  // close to it where x carries the detail (the floor reads a sixteenth of the x-lines).
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0, 1);
  BlockFitter fitter;
  const Int3 shapes[] = {{17, 9, 13}, {33, 20, 17}, {2, 7, 30}, {40, 40, 40}};
  double closest = 0;
  for (const Int3& n : shapes)
    for (int degree : {1, 2, 3})
      for (double amplitude : {0.0, 0.3, 3.0}) {
        std::vector<float> v(static_cast<size_t>(n[0]) * size_t(n[1]) * size_t(n[2]));
        size_t i = 0;
        for (int z = 0; z < n[2]; ++z)
          for (int y = 0; y < n[1]; ++y)
            for (int x = 0; x < n[0]; ++x)
              v[i++] = float(std::sin(0.7 * x) + 0.2 * y + 0.01 * z * z + amplitude * noise(rng));
        Int3 degs{};
        for (int a = 0; a < 3; ++a) degs[a] = effectiveDegree(degree, n[a]);
        const int nmax = std::max({n[0], n[1], n[2]});
        const FitResult fit =
            fitter.fit(v.data(), n, clampNcp(std::min(degree + 1, nmax), n, degs), degree);
        const double floor = fewestPointsRmseFloor(v.data(), n, degree);
        SCOPED_TRACE(testing::Message() << n[0] << "x" << n[1] << "x" << n[2] << " degree "
                                        << degree << " noise " << amplitude);
        EXPECT_LE(floor, fit.error.rmse * (1 + 1e-9));
        if (n[0] > degree + 1) closest = std::max(closest, floor / fit.error.rmse);
        // The verdict: Fails exactly where the floor is above the bound (clear of rounding: a
        // floor of rounding alone, x a line of 2 points, decides nothing), for that NCP only.
        for (const double bound : {0.5 * floor, 2 * floor}) {
          NcpVerdicts verdicts;
          const bool failed = fewestPointsFail(v.data(), n, degree, bound, verdicts);
          EXPECT_EQ(failed, bound < floor && floor > 1e-6);
          EXPECT_EQ(verdicts.at(fit.ncp, bound), failed ? Verdict::Fails : Verdict::Unknown);
          if (failed) {
            EXPECT_GT(fit.error.rmse, bound);
          }
        }
      }
  EXPECT_GT(closest, 0.2);  // a floor that can decide: a fifth of the fit's error or more
}

TEST(NcpSearch, AnInterpolantPassesWhereItsRoundingIsSureToKeepTheBound) {
  // interpolationGain bounds the interpolating spline's points by its samples' largest magnitude
  // (and is reached within a factor of 2 by the worst sign pattern); interpolantPasses gives
  // Passes for NCP = n where twice the float32 rounding is within the bound, and then the fit at
  // n does keep it; a bound below the rounding gets no verdict.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uniform(-1, 1);
  BlockFitter fitter;
  for (int degree : {1, 2, 3})
    for (const Int3& n : {Int3{17, 9, 13}, Int3{2, 7, 30}, Int3{40, 33, 1}}) {
      SCOPED_TRACE(testing::Message()
                   << n[0] << "x" << n[1] << "x" << n[2] << " degree " << degree);
      std::vector<float> v(static_cast<size_t>(n[0]) * size_t(n[1]) * size_t(n[2]));
      for (float& x : v) x = float(1000 * uniform(rng));
      double gain = 1;
      for (int a = 0; a < 3; ++a) {
        gain *= interpolationGain(n[a], degree);
        EXPECT_GE(interpolationGain(n[a], degree), 1.0);
        EXPECT_LT(interpolationGain(n[a], degree), 10.0);
      }
      const FitResult fit = fitter.fit(v.data(), n, n, degree);
      float largest = 0;
      for (const float c : fit.control) largest = std::max(largest, std::fabs(c));
      EXPECT_LE(largest, gain * 1000 * (1 + 1e-6));
      for (const double bound : {0.1, 1e-6}) {
        NcpVerdicts verdicts;
        const bool passes = interpolantPasses(v.data(), n, degree, bound, verdicts);
        EXPECT_EQ(passes, bound == 0.1);  // twice the rounding of 1000: 1.2e-4 x the gain (< 110)
        EXPECT_EQ(verdicts.at(n, bound), passes ? Verdict::Passes : Verdict::Unknown);
        if (passes) {
          EXPECT_LE(fit.error.rmse, bound);
          EXPECT_LE(fit.error.maxError, bound);
        }
      }
    }
}
