// SPDX-License-Identifier: BSD-3-Clause
// Cameras given in the world and mapped into the normalised frame (Camera::mapped: a non-cubic
// volume, a moved / rotated / scaled vtkVolume), and parallel projection: the rays land on the
// world's rays, steps keep their world length, frustum culling stays conservative, and a
// rendering through the mapped camera equals the rendering done in the world.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "afam/base/errors.hpp"
#include "afam/eval/ground_truth.hpp"
#include "afam/render/cpu_raycaster.hpp"
#include "afam/scene/camera.hpp"
#include "afam/scene/lod.hpp"

using namespace afam;

namespace {

using M3 = std::array<double, 9>;

Vec3 mul(const M3& m, const Vec3& v) {
  return {m[0] * v[0] + m[1] * v[1] + m[2] * v[2], m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
          m[6] * v[0] + m[7] * v[1] + m[8] * v[2]};
}
M3 mul(const M3& a, const M3& b) {
  M3 c{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) c[3 * i + j] += a[3 * i + k] * b[3 * k + j];
  return c;
}
double norm(const Vec3& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

/// Rotation about z by a, then about x by b (row-major).
M3 rotation(double a, double b) {
  const M3 rz{std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1};
  const M3 rx{1, 0, 0, 0, std::cos(b), -std::sin(b), 0, std::sin(b), std::cos(b)};
  return mul(rx, rz);
}

/// World -> normalised frame of a volume whose box is centre c, half extents h, optionally
/// rotated by R (world = R data): x' = S R^T (x - c).
struct VolumeMap {
  M3 linear;
  Vec3 offset;
};
VolumeMap volumeMap(const Vec3& c, const Vec3& h, const M3& r) {
  const M3 rt{r[0], r[3], r[6], r[1], r[4], r[7], r[2], r[5], r[8]};
  const M3 s{1 / h[0], 0, 0, 0, 1 / h[1], 0, 0, 0, 1 / h[2]};
  VolumeMap m{mul(s, rt), {}};
  const Vec3 lc = mul(m.linear, c);
  m.offset = {-lc[0], -lc[1], -lc[2]};
  return m;
}

Camera worldCamera(bool parallel, const Vec3& eye, const Vec3& focal, int w, int h) {
  return parallel ? Camera::parallelLookAt(eye, focal, {0.2, 1, 0.1}, 1.7, w, h)
                  : Camera::lookAt(eye, focal, {0.2, 1, 0.1}, 30.0, w, h);
}

}  // namespace

TEST(MappedCamera, PixelRaysLandOnTheWorldRays) {
  const VolumeMap m = volumeMap({0.5, -1, 2}, {3, 1, 0.5}, rotation(0.4, -0.3));
  for (bool parallel : {false, true}) {
    const Camera world = worldCamera(parallel, {6, 4, 9}, {0.5, -1, 2}, 40, 30);
    const Camera mapped = world.mapped(m.linear, m.offset);
    EXPECT_TRUE(mapped.hasStepMetric);  // anisotropic: not a similarity
    const RayCamera rw = world.toRayCamera(), rm = mapped.toRayCamera();
    for (int py : {0, 7, 29})
      for (int px : {0, 13, 39}) {
        float ow[3], dw[3], om[3], dm[3];
        pixelRay(rw, px, py, ow, dw);
        pixelRay(rm, px, py, om, dm);
        // Two points of the world ray, mapped, must lie on the mapped ray.
        for (double s : {0.0, 5.0}) {
          const Vec3 pw{ow[0] + s * dw[0], ow[1] + s * dw[1], ow[2] + s * dw[2]};
          Vec3 pm = mul(m.linear, pw);
          for (int a = 0; a < 3; ++a)
            pm[a] += m.offset[a] - om[a];  // relative to the mapped origin
          const double along = pm[0] * dm[0] + pm[1] * dm[1] + pm[2] * dm[2];
          const Vec3 off{pm[0] - along * dm[0], pm[1] - along * dm[1], pm[2] - along * dm[2]};
          EXPECT_LT(norm(off), 2e-5) << "parallel " << parallel << " pixel " << px << "," << py;
          EXPECT_GT(along, -1e-5);
        }
        if (parallel) {  // every ray along the same direction
          float d0[3], o0[3];
          pixelRay(rm, 0, 0, o0, d0);
          for (int a = 0; a < 3; ++a) EXPECT_FLOAT_EQ(dm[a], d0[a]);
        }
      }
  }
}

TEST(MappedCamera, StepsKeepTheirWorldLength) {
  const VolumeMap m = volumeMap({0, 0, 0}, {4, 1, 0.25}, rotation(1.1, 0.2));
  const Camera mapped = worldCamera(false, {5, 3, 7}, {0, 0, 0}, 16, 16).mapped(m.linear, m.offset);
  ASSERT_TRUE(mapped.hasStepMetric);
  EXPECT_NEAR(mapped.lengthUnit, 1.0, 1e-12);  // 4 * 1 * 0.25 = 1: unit volume scale
  const RayCamera r = mapped.toRayCamera();
  // World length of a normalised direction: |L^-1 d|. Steps must all be sampleDistance long.
  double shortest = 1e9, longest = 0;
  for (int py = 0; py < 16; py += 5)
    for (int px = 0; px < 16; px += 5) {
      float o[3], d[3];
      pixelRay(r, px, py, o, d);
      const float dt = rayStep(r, d, 0.01f);
      // World displacement of the step: solve L x = dt d (L = S R^T, so x = R S^-1 dt d).
      const Vec3 sd{4.0 * dt * d[0], 1.0 * dt * d[1], 0.25 * dt * d[2]};
      const double len = norm(mul(rotation(1.1, 0.2), sd));
      EXPECT_NEAR(len, 0.01, 1e-7);
      shortest = std::min(shortest, double(dt));
      longest = std::max(longest, double(dt));
    }
  EXPECT_GT(longest / shortest, 1.5);  // the normalised steps do differ by direction
  // A similarity (uniform scale 1/2 and a rotation) needs no metric; lengthUnit is 2.
  const VolumeMap sim = volumeMap({1, 2, 3}, {2, 2, 2}, rotation(0.7, 0.5));
  const Camera s = worldCamera(false, {5, 3, 7}, {0, 0, 0}, 8, 8).mapped(sim.linear, sim.offset);
  EXPECT_FALSE(s.hasStepMetric);
  EXPECT_NEAR(s.lengthUnit, 2.0, 1e-12);
  EXPECT_EQ(s.toRayCamera().hasStepMetric, 0);
}

TEST(MappedCamera, RejectsSingularMapsAndBadParallelScales) {
  const Camera c = worldCamera(false, {5, 3, 7}, {0, 0, 0}, 8, 8);
  EXPECT_THROW(c.mapped({1, 0, 0, 0, 1, 0, 0, 0, 0}, {0, 0, 0}), InvalidArgument);
  EXPECT_THROW(c.mapped({1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, NAN, 0}), InvalidArgument);
  EXPECT_THROW(Camera::parallelLookAt({0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 0.0, 8, 8), InvalidArgument);
  EXPECT_THROW(Camera::parallelLookAt({0, 0, 5}, {0, 0, 0}, {0, 1, 0}, NAN, 8, 8), InvalidArgument);
  EXPECT_THROW(Camera::parallelLookAt({0, 0, 5}, {0, 0, 5}, {0, 1, 0}, 1.0, 8, 8), InvalidArgument);
}

// The same Marschner-Lobb volume ray cast (unshaded) twice: in the world, where its box is
// [-2, 2] x [-1, 1] x [-0.5, 0.5] moved to (0.3, -0.2, 0.1) and rotated, by an orthonormal world
// camera; and in the normalised frame by the mapped camera. Sample points, steps and opacities
// coincide, so the images must agree to float rounding.
TEST(MappedCamera, RenderingThroughTheMapEqualsRenderingInTheWorld) {
  const Vec3 centre{0.3, -0.2, 0.1}, half{2, 1, 0.5};
  const M3 rot = rotation(0.5, 0.35);
  const VolumeMap m = volumeMap(centre, half, rot);
  // A transfer function with several opacities so that compositing order and steps matter.
  const std::vector<float> tf = {0.2f, 0.1f, 0.0f, 0.00f, 0.9f, 0.3f, 0.1f, 0.05f,
                                 0.1f, 0.8f, 0.3f, 0.15f, 1.0f, 1.0f, 0.9f, 0.30f};
  for (bool parallel : {false, true}) {
    const Camera world = worldCamera(parallel, {4.5, 3.5, 6.0}, centre, 48, 40);
    const Camera mapped = world.mapped(m.linear, m.offset);
    // World frame: the box is axis-aligned in the volume's own (rotated) frame, so render the
    // world in that frame: world camera vectors rotated by R^T, box centred at 0 with half
    // extents h (a rigid motion changes no lengths, steps or opacities).
    const M3 rt{rot[0], rot[3], rot[6], rot[1], rot[4], rot[7], rot[2], rot[5], rot[8]};
    Camera local = world;
    Vec3 e{world.eye[0] - centre[0], world.eye[1] - centre[1], world.eye[2] - centre[2]};
    local.eye = mul(rt, e);
    local.right = mul(rt, world.right);
    local.up = mul(rt, world.up);
    local.forward = mul(rt, world.forward);
    const float sd = 0.004f;
    auto view = [&](const Camera& c, const Vec3& lo, const Vec3& hi, float sampleDistance) {
      FrameView f;
      f.camera = c.toRayCamera();
      for (int a = 0; a < 3; ++a) {
        f.boxLo[a] = float(lo[a]);
        f.boxHi[a] = float(hi[a]);
      }
      f.tf = tf.data();
      f.tfSize = 4;
      f.tfMin = 0.f;
      f.tfMax = 1.f;
      f.sampleDistance = sampleDistance;
      f.tfReferenceDistance = 2.f * sampleDistance;  // a real pow() correction, same in both
      f.shading = 0;
      return f;
    };
    const FrameView fw =
        view(local, {-half[0], -half[1], -half[2]}, half, float(sd * mapped.lengthUnit));
    const FrameView fm = view(mapped, {-1, -1, -1}, {1, 1, 1}, sd);
    ImageRGBA iw, im;
    renderCpuWith(fw, MarschnerLobbSampler{}, iw, 1);
    renderCpuWith(fm, MarschnerLobbSampler{}, im, 1);
    ASSERT_EQ(iw.rgba.size(), im.rgba.size());
    double worst = 0, covered = 0;
    for (size_t i = 0; i < iw.rgba.size(); ++i)
      worst = std::max(worst, double(std::abs(iw.rgba[i] - im.rgba[i])));
    for (size_t i = 3; i < iw.rgba.size(); i += 4) covered += iw.rgba[i] > 0.01f;
    EXPECT_LT(worst, 1e-4) << (parallel ? "parallel" : "perspective");
    std::printf("[mapped] %s: worst |world - mapped| %.2e over %zu values\n",
                parallel ? "parallel" : "perspective", worst, iw.rgba.size());
    EXPECT_GT(covered, 0.2 * iw.width * iw.height);  // the volume fills a good part of the view
    // Without the step metric the mapped rendering is visibly different (steps of the wrong
    // world length: the opacity is off), so the test above is not passing by accident.
    FrameView wrong = fm;
    wrong.camera.hasStepMetric = 0;
    ImageRGBA iwrong;
    renderCpuWith(wrong, MarschnerLobbSampler{}, iwrong, 1);
    double off = 0;
    for (size_t i = 0; i < iw.rgba.size(); ++i)
      off = std::max(off, double(std::abs(iw.rgba[i] - iwrong.rgba[i])));
    EXPECT_GT(off, 0.02);
  }
}

// A magnified screenshot: VTK renders n x n tiles of the window's size, each with the view angle
// (or parallel scale) divided by n and WindowCenter moved to the tile (Camera::centerX/Y). The
// tiles must reassemble the image rendered at n times the size in one go.
TEST(MappedCamera, OffCentreTilesReassembleTheFullImage) {
  const int n = 3, tw = 20, th = 16;
  const std::vector<float> tf = {0.2f, 0.1f, 0.0f, 0.00f, 0.9f, 0.3f, 0.1f, 0.05f,
                                 0.1f, 0.8f, 0.3f, 0.15f, 1.0f, 1.0f, 0.9f, 0.30f};
  auto view = [&](const Camera& c) {
    FrameView f;
    f.camera = c.toRayCamera();
    f.tf = tf.data();
    f.tfSize = 4;
    f.sampleDistance = 0.004f;
    f.tfReferenceDistance = 0.008f;
    f.shading = 0;
    return f;
  };
  for (bool parallel : {false, true}) {
    const Camera full = worldCamera(parallel, {2.5, 1.5, 3.5}, {0.1, 0, 0}, n * tw, n * th);
    ImageRGBA whole;
    renderCpuWith(view(full), MarschnerLobbSampler{}, whole, 1);
    double worst = 0, covered = 0;
    for (int j = 0; j < n; ++j)      // tile row, 0 = top
      for (int i = 0; i < n; ++i) {  // tile column, 0 = left
        Camera tile = full;
        tile.width = tw;
        tile.height = th;
        tile.tanHalfX = full.tanHalfX / n;
        tile.tanHalfY = full.tanHalfY / n;
        tile.centerX = (-1.0 + (2.0 * i + 1) / n) * full.tanHalfX;
        tile.centerY = (1.0 - (2.0 * j + 1) / n) * full.tanHalfY;
        ImageRGBA part;
        renderCpuWith(view(tile), MarschnerLobbSampler{}, part, 1);
        for (int y = 0; y < th; ++y)
          for (int x = 0; x < tw; ++x)
            for (int k = 0; k < 4; ++k) {
              const float a = part.rgba[(size_t(y) * tw + x) * 4 + k];
              const float b = whole.rgba[(size_t(j * th + y) * (n * tw) + (i * tw + x)) * 4 + k];
              worst = std::max(worst, double(std::abs(a - b)));
              if (k == 3) covered += b > 0.01f;
            }
        // Culling through the tile's frustum keeps every block the tile's rays reach: checked
        // against the whole image's rays that fall in this tile.
        const Partition p({33, 33, 33}, 2, 4);
        const RayCamera wr = full.toRayCamera();
        for (int y = 0; y < th; y += 5)
          for (int x = 0; x < tw; x += 5) {
            float o[3], d[3];
            pixelRay(wr, i * tw + x, j * th + y, o, d);
            for (double t = 0.05; t < 8; t += 0.1) {
              const double q[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
              if (std::abs(q[0]) > 1 || std::abs(q[1]) > 1 || std::abs(q[2]) > 1) continue;
              for (int bz = 0; bz < 4; ++bz)
                for (int by = 0; by < 4; ++by)
                  for (int bx = 0; bx < 4; ++bx) {
                    double lo[3], hi[3];
                    blockBox(p, 1, {bx, by, bz}, lo, hi);
                    if (q[0] >= lo[0] && q[0] <= hi[0] && q[1] >= lo[1] && q[1] <= hi[1] &&
                        q[2] >= lo[2] && q[2] <= hi[2]) {
                      ASSERT_FALSE(LodSelector::outsideFrustum(tile, lo, hi));
                    }
                  }
            }
          }
      }
    std::printf("[tiles] %s: worst |tile - whole| %.2e\n", parallel ? "parallel" : "perspective",
                worst);
    EXPECT_LT(worst, 1e-4);
    EXPECT_GT(covered, 0.2 * n * tw * n * th);
  }
}

TEST(MappedCamera, FrustumCullingStaysConservative) {
  const Partition p({65, 65, 65}, 3, 8);
  const LodSelector sel;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u01(0, 1);
  int culled = 0, checked = 0;
  for (int i = 0; i < 16; ++i) {
    const bool parallel = i % 2 == 1;
    const VolumeMap m = volumeMap({0, 0, 0}, {1 + 3 * u01(rng), 1, 0.3 + u01(rng)},
                                  rotation(6 * u01(rng), 3 * u01(rng)));
    // Close to (or inside) the volume, looking across it: a 30-degree view (or a parallel one
    // narrower than the volume) leaves blocks out.
    const Vec3 eye{2 * (u01(rng) - 0.5), 2 * (u01(rng) - 0.5), 0.5 + 1.5 * u01(rng)};
    Camera world = worldCamera(parallel, eye, {2 * (u01(rng) - 0.5), 0.3, -1}, 24, 16);
    if (parallel) world.tanHalfY = 0.2 + 0.3 * u01(rng), world.tanHalfX = 1.5 * world.tanHalfY;
    if (i % 4 >= 2) {  // off-centre frustums too (screenshot tiles)
      world.centerX = 2 * (u01(rng) - 0.5) * world.tanHalfX;
      world.centerY = 2 * (u01(rng) - 0.5) * world.tanHalfY;
    }
    const Camera c = world.mapped(m.linear, m.offset);
    const RayCamera r = c.toRayCamera();
    const auto cut = sel.cut(p, c);
    for (const BlockRef& b : cut) {
      double lo[3], hi[3];
      blockBox(p, b.level, b.ijk, lo, hi);
      culled += LodSelector::outsideFrustum(c, lo, hi);
    }
    // Points on pixel rays (image corners included) inside the volume lie in non-culled blocks.
    for (int py = 0; py < 16; py += 3)
      for (int px = 0; px < 24; px += 3) {
        float o[3], d[3];
        pixelRay(r, px, py, o, d);
        for (double t = c.nearDistance + 0.01; t < 20; t += 0.05) {
          const double q[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
          if (std::abs(q[0]) > 1 || std::abs(q[1]) > 1 || std::abs(q[2]) > 1) continue;
          for (const BlockRef& b : cut) {
            double lo[3], hi[3];
            blockBox(p, b.level, b.ijk, lo, hi);
            if (q[0] >= lo[0] && q[0] <= hi[0] && q[1] >= lo[1] && q[1] <= hi[1] && q[2] >= lo[2] &&
                q[2] <= hi[2]) {
              ++checked;
              ASSERT_FALSE(LodSelector::outsideFrustum(c, lo, hi)) << "view " << i;
            }
          }
        }
      }
  }
  EXPECT_GT(checked, 1000);
  EXPECT_GT(culled, 100);
}
