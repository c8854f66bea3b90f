// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <type_traits>

#include "afam/format/partition.hpp"
#include "afam/render/raycast.hpp"

using namespace afam;

static_assert(std::is_trivially_copyable<FrameView>::value, "FrameView goes to kernels by value");
static_assert(std::is_trivially_copyable<FrameSlot>::value,
              "FrameSlot goes to the device as bytes");

TEST(Raycast, ConstantTimeLookupEqualsBruteForce) {
  for (const Index3 dims : {Index3{65, 65, 65}, Index3{50, 33, 71}, Index3{100, 7, 2}}) {
    const Partition p(dims, 3, 16);
    const int finest = p.levels() - 1;
    const Int3 bf = p.blocksPerAxis(finest);
    std::vector<float> bounds[3];
    FrameView f;
    for (int a = 0; a < 3; ++a) {
      for (int i = 0; i < bf[a]; ++i) {
        Int3 ijk{0, 0, 0};
        ijk[a] = i;
        const BlockExtent e = p.extent(finest, ijk);
        if (i == 0) bounds[a].push_back(float(e.lo[a]));
        bounds[a].push_back(float(e.hi[a]));
      }
      f.gridDims[a] = bf[a];
      f.cellPerVoxel[a] = float(bf[a]) / float(dims[a] - 1);
      f.cellBounds[a] = bounds[a].data();
      f.voxelMax[a] = float(dims[a] - 1);
    }
    std::vector<int32_t> cells(static_cast<size_t>(bf[0]) * bf[1] * bf[2]);
    for (size_t i = 0; i < cells.size(); ++i) cells[i] = int32_t(i);
    f.cellSlot = cells.data();
    std::mt19937 rng(5);
    for (int k = 0; k < 20000; ++k) {
      float x[3];
      int brute[3];
      for (int a = 0; a < 3; ++a) {
        // Half the points exactly on a boundary, half uniform.
        if (k % 2) {
          x[a] = bounds[a][std::uniform_int_distribution<size_t>(0, bounds[a].size() - 1)(rng)];
        } else {
          x[a] = std::uniform_real_distribution<float>(0.f, float(dims[a] - 1))(rng);
        }
        int c = 0;  // brute force: last cell whose lower bound <= x
        for (int i = 0; i < bf[a]; ++i)
          if (x[a] >= bounds[a][size_t(i)]) c = i;
        brute[a] = c;
      }
      const int32_t got = lookupSlot(f, x);
      ASSERT_EQ(got, int32_t((brute[2] * bf[1] + brute[1]) * bf[0] + brute[0]));
    }
  }
}

TEST(Raycast, RawSlotIsExactForLinearFunctions) {
  // Padded 4 x 5 x 3 block (real samples 2 x 3 x 1), f = 1 + 2x + 3y (voxel units), extent
  // lo = (10, 20, 5), hi = (14, 28, 5): sample spacing 4 and 4 voxels.
  FrameSlot s;
  s.kind = kSlotRaw;
  const int n[3] = {4, 5, 3};
  for (int a = 0; a < 3; ++a) s.knots[a].ncp = n[a];
  s.lo[0] = 10, s.lo[1] = 20, s.lo[2] = 5;
  s.invExtent[0] = 1.f / 4, s.invExtent[1] = 1.f / 8, s.invExtent[2] = 0;
  std::vector<float> data(4 * 5 * 3);
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i < 4; ++i) {
        const float x = 10 + (i - 1) * 4.f, y = 20 + (j - 1) * 4.f;
        data[size_t((k * 5 + j) * 4 + i)] = 1 + 2 * x + 3 * y;
      }
  const float x[3] = {11.5f, 25.f, 5.f};
  float g[3];
  const float v = sampleRawSlot<true>(s, data.data(), x, g);
  EXPECT_NEAR(v, 1 + 2 * 11.5f + 3 * 25.f, 1e-4);
  EXPECT_NEAR(g[0], 2.f, 1e-5);
  EXPECT_NEAR(g[1], 3.f, 1e-5);
  EXPECT_NEAR(g[2], 0.f, 1e-6);
}

TEST(Raycast, SplineSlotMatchesEvaluateModelAndScalesTheGradient) {
  FrameSlot s;
  s.kind = kSlotSpline;
  for (int a = 0; a < 3; ++a) s.knots[a] = Knots::make(4, 2);
  s.lo[0] = 2, s.lo[1] = 4, s.lo[2] = 8;
  s.invExtent[0] = 1.f / 8, s.invExtent[1] = 1.f / 16, s.invExtent[2] = 1.f / 4;
  std::vector<float> cp(64);
  for (size_t i = 0; i < cp.size(); ++i) cp[i] = float(std::sin(0.7 * double(i)));
  const float x[3] = {5.f, 9.f, 10.f};
  float g[3];
  const float v = sampleSplineSlot<true>(s, cp.data(), x, g);
  ModelView m;
  for (int a = 0; a < 3; ++a) m.knots[a] = s.knots[a];
  m.control = cp.data();
  float gu[3];
  const float ref = evaluateModel<true>(m, 3.f / 8, 5.f / 16, 2.f / 4, gu);
  EXPECT_FLOAT_EQ(v, ref);
  EXPECT_FLOAT_EQ(g[0], gu[0] / 8);
  EXPECT_FLOAT_EQ(g[1], gu[1] / 16);
  EXPECT_FLOAT_EQ(g[2], gu[2] / 4);
  EXPECT_FLOAT_EQ(sampleSplineSlot<false>(s, cp.data(), x, nullptr), ref);
}

TEST(Raycast, ClassifyCompositeAndTerminate) {
  FrameView f;
  const float tf[8] = {0, 0, 0, 0, 1, 0.5f, 0.25f, 1};
  f.tf = tf;
  f.tfSize = 2;
  f.tfMin = 0;
  f.tfMax = 2;
  const RGBA c = classify(f, 1.f);
  EXPECT_FLOAT_EQ(c.r, 0.5f);
  EXPECT_FLOAT_EQ(c.g, 0.25f);
  EXPECT_FLOAT_EQ(c.a, 0.5f);
  EXPECT_FLOAT_EQ(classify(f, 5.f).a, 1.f);
  EXPECT_FLOAT_EQ(classify(f, -5.f).a, 0.f);
  // Opacity correction: two half-distance samples compose to one full-distance sample.
  const float half = correctOpacity(0.5f, 0.5f);
  EXPECT_NEAR(1 - (1 - half) * (1 - half), 0.5f, 1e-6);
  RGBA acc;
  compositeFrontToBack(acc, RGBA{1, 0, 0, 0.5f});
  compositeFrontToBack(acc, RGBA{0, 1, 0, 0.5f});
  EXPECT_FLOAT_EQ(acc.r, 0.5f);
  EXPECT_FLOAT_EQ(acc.g, 0.25f);
  EXPECT_FLOAT_EQ(acc.a, 0.75f);
}

namespace {
/// A constant-field sampler: opaque everywhere inside the box, counts its calls.
struct CountingSampler {
  mutable int calls = 0;
  template <bool G>
  bool sample(const FrameView&, const float*, float& v, float* g) const {
    ++calls;
    v = 1.f;
    if (G) g[0] = g[1] = g[2] = 0.f;
    return true;
  }
};

/// A view of the constant field through a two-entry table `tf` (alpha per 0.01 sample step),
/// eye at (0, 0, eyeZ) looking down -z, one pixel.
FrameView constantFieldView(const float* tf, float eyeZ) {
  FrameView f;
  f.tf = tf;
  f.tfSize = 2;
  f.sampleDistance = 0.01f;
  f.tfReferenceDistance = 0.01f;
  f.camera.eye[2] = eyeZ;
  f.camera.width = f.camera.height = 1;
  return f;
}
}  // namespace

TEST(Raycast, EarlyTerminationAndNearPlaneInsideTheBox) {
  const float tf[8] = {0, 0, 0, 0.2f, 1, 1, 1, 0.2f};
  FrameView f = constantFieldView(tf, 0.f);  // inside the box, looking down -z
  CountingSampler s;
  const RGBA c = castRayWith<false>(f, s, 0, 0);
  EXPECT_GE(c.a, kTerminationOpacity);
  // 1 - 0.8^n >= 1 - 1/255 from n = 25 (the first sample's end weight may save one)
  EXPECT_NEAR(kTerminationOpacity, 1.f - 1.f / 255.f, 1e-7f);
  EXPECT_LE(s.calls, 25);
  EXPECT_GE(s.calls, 24);
  f.camera.eye[2] = 5.f;
  f.camera.forward[2] = 1.f;  // looking away: misses the box
  CountingSampler s2;
  EXPECT_EQ(castRayWith<true>(f, s2, 0, 0).a, 0.f);
  EXPECT_EQ(s2.calls, 0);
}

TEST(Raycast, MaxDistanceStopsTheRayAtOpaqueGeometry) {
  // Faint constant field (alpha 0.01 per sample: no early termination within the box): eye at
  // z = 5 looking down -z, the box spans t in [4, 6]. Three pixels: no geometry (+inf), a surface
  // at t = 4.5 (a quarter of the box's depth), a surface in front of the box (t = 3).
  const float tf[8] = {0, 0, 0, 0.01f, 1, 1, 1, 0.01f};
  FrameView f = constantFieldView(tf, 5.f);
  f.camera.tanHalfX = f.camera.tanHalfY = 1e-4f;  // all three rays nearly along the axis
  f.camera.width = 3;
  f.camera.height = 1;
  CountingSampler free, limited, hidden, unset;
  const RGBA noLimit = castRayWith<false>(f, unset, 0, 0);
  const float depth[3] = {INFINITY, 4.5f, 3.f};
  f.maxDistance = depth;
  const RGBA a = castRayWith<false>(f, free, 0, 0);
  const RGBA b = castRayWith<false>(f, limited, 1, 0);
  const RGBA c = castRayWith<false>(f, hidden, 2, 0);
  // +inf changes nothing.
  EXPECT_EQ(free.calls, unset.calls);
  EXPECT_FLOAT_EQ(a.a, noLimit.a);
  EXPECT_NEAR(free.calls, 201, 1);    // t = 4.00 .. 6.00
  EXPECT_NEAR(limited.calls, 51, 1);  // t = 4.00 .. 4.50
  EXPECT_EQ(hidden.calls, 0);
  EXPECT_EQ(c.a, 0.f);
  // The first and last samples stand for the ray's ends (endWeight): the opacity of exactly the
  // ray's length in the box, 4.00 .. 4.50, 50 steps, whatever the samples' count.
  EXPECT_NEAR(b.a, 1.f - std::pow(0.99f, 50.f), 1e-5);
  EXPECT_NEAR(a.a, 1.f - std::pow(0.99f, 200.f), 1e-5);
  EXPECT_LT(b.a, 0.7f * a.a);
}

TEST(Raycast, OpacityOfTheRaysLengthWhereverTheBoxCutsTheLattice) {
  // The eye moves by parts of a step, with and without jitter: a ray through the faint constant
  // field gathers the opacity of its length in the box (2.00, 200 steps) at every offset, not 200
  // or 201 whole samples by turns (a grid pattern on the volume's faces, in images).
  const float tf[8] = {0, 0, 0, 0.01f, 1, 1, 1, 0.01f};
  const float want = 1.f - std::pow(0.99f, 200.f);
  for (int i = 0; i < 10; ++i) {
    FrameView f = constantFieldView(tf, 5.f + 0.001f * float(i));
    f.jitter = i % 2;
    CountingSampler s;
    EXPECT_NEAR(castRayWith<false>(f, s, 0, 0).a, want, 2e-5) << "eye offset " << i << "/10 step";
  }
}

namespace {
/// value = z of the sample point (a linear field), for the projection tests.
struct DepthSampler {
  template <bool G>
  bool sample(const FrameView&, const float* p, float& v, float* g) const {
    v = p[2];
    if (G) g[0] = g[1] = 0.f, g[2] = 1.f;
    return true;
  }
};
}  // namespace

TEST(Raycast, ProjectionsTakeTheLargestSmallestAndMeanValueOfTheRay) {
  // Table over [-1, 1]: colour (v + 1) / 2 in every channel, alpha 0.2 at -1 to 0.8 at 1. Eye at
  // z = 5 looking down -z: the ray's samples run from z = 1 (t = 4) to z = -1 (t = 6).
  const float tf[8] = {0, 0, 0, 0.2f, 1, 1, 1, 0.8f};
  FrameView f = constantFieldView(tf, 5.f);
  f.tfMin = -1.f;
  f.tfMax = 1.f;
  f.camera.tanHalfX = f.camera.tanHalfY = 1e-4f;
  auto expect = [](const RGBA& c, float v, const char* what) {
    const float a = 0.2f + 0.3f * (v + 1.f), col = 0.5f * (v + 1.f);
    EXPECT_NEAR(c.a, a, 2e-3) << what;
    EXPECT_NEAR(c.r, col * a, 2e-3) << what;  // premultiplied
    EXPECT_NEAR(c.b, col * a, 2e-3) << what;
  };
  const DepthSampler s;
  f.blendMode = kBlendMaximum;
  expect(castProjectionRayWith(f, s, 0, 0), 1.f, "maximum");
  f.blendMode = kBlendMinimum;
  expect(castProjectionRayWith(f, s, 0, 0), -1.f, "minimum");
  // Average (VTK's convention): an opaque grey, the mean of alpha(v) (v - tfMin) / (tfMax - tfMin):
  // here the mean of (0.5 + 0.3 z) (z + 1) / 2 over z in [-1, 1] = 0.3 (0.25 + 0.1 / 3 ... see
  // below). For samples uniform in z on [a, b]: mean of (0.5 + 0.3 z)(z + 1)/2 = (1/2)(0.5 + 0.8 m
  // + 0.3 q), m = mean z, q = mean z^2.
  auto expectGrey = [](const RGBA& c, float grey, const char* what) {
    EXPECT_NEAR(c.a, 1.f, 1e-6) << what;
    EXPECT_NEAR(c.r, grey, 2e-3) << what;
    EXPECT_NEAR(c.g, grey, 2e-3) << what;
  };
  auto averageOf = [](double a, double b) {
    const double m = 0.5 * (a + b), q = (a * a + a * b + b * b) / 3.0;
    return float(0.5 * (0.5 + 0.8 * m + 0.3 * q));
  };
  f.blendMode = kBlendAverage;
  expectGrey(castProjectionRayWith(f, s, 0, 0), averageOf(-1, 1), "average");
  // Opaque geometry at t = 5 (z = 0): the samples behind it do not count.
  const float limit[1] = {5.f};
  f.maxDistance = limit;
  f.blendMode = kBlendMinimum;
  expect(castProjectionRayWith(f, s, 0, 0), 0.f, "minimum, cut at z = 0");
  f.blendMode = kBlendAverage;
  expectGrey(castProjectionRayWith(f, s, 0, 0), averageOf(0, 1), "average, cut at z = 0");
  f.blendMode = kBlendMaximum;
  expect(castProjectionRayWith(f, s, 0, 0), 1.f, "maximum, cut at z = 0");
  // A ray that misses the box: nothing.
  f.camera.forward[2] = 1.f;
  EXPECT_EQ(castProjectionRayWith(f, s, 0, 0).a, 0.f);
}
