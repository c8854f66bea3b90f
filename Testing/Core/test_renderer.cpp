// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <set>
#include <tuple>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/eval/ground_truth.hpp"
#include "afam/eval/image_metrics.hpp"
#include "afam/eval/png_io.hpp"
#include "afam/render/cpu_raycaster.hpp"
#include "afam/render/renderer.hpp"
#include "render_test_util.hpp"
#include "scratch_dir.hpp"

using namespace afam;

namespace {

Camera testCamera(int size = 64) {
  return Camera::lookAt({1.1, 1.3, 0.9}, {0, 0, 0}, {0, 0, 1}, 60, size, size);
}

/// finestOnly: a band width no distance reaches, so every block is finest (model error only).
RenderOptions testOptions(bool finestOnly = false) {
  RenderOptions o;
  if (finestOnly) o.lod.bandWidth = 100;
  o.threads = 2;
  o.sampleDistance = 0.01f;
  o.cache = CacheBudget{};
  return o;
}

ImageRGBA groundTruth(Renderer& r, const Camera& c) {
  PreparedFrame fr;
  r.prepareEmpty(c, fr);
  ImageRGBA img;
  renderCpuWith(fr.view, MarschnerLobbSampler{}, img, 2);
  return img;
}

double psnrOf(const ImageRGBA& a, const ImageRGBA& b) { return compare(toRGB8(a), toRGB8(b)).psnr; }

}  // namespace

TEST(Renderer, AdaptiveFamMatchesTheAnalyticGroundTruth) {
  auto file = afam_test::encodeMl(65, EncodingMode::Adaptive, 3, 4, 1e-3);
  Renderer r(file, testOptions(true));
  const Camera c = testCamera();
  FrameStats st;
  const ImageRGBA img = r.renderFrame(c, st);
  const ImageRGBA gt = groundTruth(r, c);
  const double p = psnrOf(img, gt);
  RecordProperty("psnr", std::to_string(p));
  std::printf("adaptive psnr=%.2f ssim=%.4f slots=%lld\n", p, compare(toRGB8(img), toRGB8(gt)).ssim,
              (long long)st.slots);
  EXPECT_GT(p, 37.0);  // measured 40.4 (65^3, bound 1e-3, preset TF, 64 x 64)
  EXPECT_GT(st.slots, 0);
  EXPECT_GT(st.misses, 0u);
  EXPECT_EQ(st.hits, 0u);
  // The same frame again: every block hits, nothing is read.
  FrameStats st2;
  r.renderFrame(c, st2);
  EXPECT_EQ(st2.misses, 0u);
  EXPECT_EQ(st2.bytesRead, 0u);
  EXPECT_EQ(st2.hits, st.misses);
}

TEST(Renderer, DownsampledFileRendersWithRawSlots) {
  auto file = afam_test::encodeMl(65, EncodingMode::Downsampled, 3, 4);
  Renderer r(file, testOptions(true));
  const Camera c = testCamera();
  FrameStats st;
  const ImageRGBA img = r.renderFrame(c, st);
  const double p = psnrOf(img, groundTruth(r, c));
  std::printf("ds psnr=%.2f\n", p);
  EXPECT_GT(p, 27.0);  // measured 30.0: trilinear on 65^3 ML, central-difference normals
}

TEST(Renderer, CulledRenderEqualsUnculledRender) {
  auto file = afam_test::encodeMl(65, EncodingMode::Adaptive, 3, 8, 1e-3);
  TransferFunction tf;  // transparent below 55% of the range: the upper (low-valued) ML half culls
  tf.colors = {{0.0, 0.2, 0.3, 0.9}, {1.0, 0.9, 0.4, 0.1}};
  tf.opacities = {{0.0, 0.0}, {0.55, 0.0}, {0.8, 0.3}, {1.0, 0.5}};
  int64_t frustum = 0, tfCulled = 0;
  for (bool shading : {true, false}) {
    RenderOptions on = testOptions(), off = testOptions();
    for (RenderOptions* o : {&on, &off}) {
      o->shading = shading;
      o->lod.bandWidth = 0.4;
      o->hasTransferFunction = true;
      o->transferFunction = tf;
    }
    RenderOptions tfOn = on;
    off.lod.frustumCulling = off.lod.tfCulling = false;
    tfOn.lod.frustumCulling = false;
    Renderer a(file, on), b(file, off), tfOnly(file, tfOn);
    for (const Camera& c : {testCamera(48), Camera::fromPose({1.2, 60, 30}, 48, 48)}) {
      FrameStats sa, sb;
      const ImageRGBA ia = a.renderFrame(c, sa), ib = b.renderFrame(c, sb);
      frustum += sa.culled.frustumBlocks;
      tfCulled += sa.culled.tfBlocks;
      EXPECT_EQ(sb.culled.frustumBlocks + sb.culled.tfBlocks, 0);
      // The culled cut is the unculled one less its blocks outside the frustum or the transfer
      // function (those outside the frustum are not refined: counted at a coarser level).
      using Key = std::tuple<int, int, int, int>;
      const auto keys = [](const Selection& sel) {
        std::set<Key> out;
        for (const BlockRef& r : sel.visible) out.insert({r.level, r.ijk[0], r.ijk[1], r.ijk[2]});
        return out;
      };
      std::set<Key> kept = keys(a.select(c));
      const std::set<Key> tfKept = keys(tfOnly.select(c));
      int64_t dropped = 0;
      for (const BlockRef& r : b.select(c).visible) {
        const Key k{r.level, r.ijk[0], r.ijk[1], r.ijk[2]};
        if (kept.erase(k)) continue;
        double lo[3], hi[3];
        blockBox(file->partition(), r.level, r.ijk, lo, hi);
        EXPECT_TRUE(LodSelector::outsideFrustum(c, lo, hi) || !tfKept.count(k))
            << "a drawn block was culled: level " << r.level;
        ++dropped;
      }
      EXPECT_TRUE(kept.empty()) << "the culled cut drew a block the unculled one did not";
      EXPECT_EQ(sa.slots + dropped, sb.slots);
      EXPECT_GE(dropped, sa.culled.frustumBlocks + sa.culled.tfBlocks);
      EXPECT_LE(sa.culled.visibleBytes, sb.culled.visibleBytes);
      double maxDiff = 0;
      for (size_t i = 0; i < ia.rgba.size(); ++i)
        maxDiff = std::max(maxDiff, double(std::abs(ia.rgba[i] - ib.rgba[i])));
      EXPECT_LE(maxDiff, 1e-6);
    }
  }
  EXPECT_GT(frustum, 0);
  EXPECT_GT(tfCulled, 0);
}

TEST(Renderer, ModelSamplerReproducesGridValues) {
  // At grid points DS returns the samples and the spline fits them within the encoding bound.
  const MarschnerLobb ml;
  for (EncodingMode mode : {EncodingMode::Downsampled, EncodingMode::Adaptive}) {
    auto file = afam_test::encodeMl(65, mode, 3, 4, 1e-3);
    PreparedFrame fr;
    FrameStats st;
    RenderOptions o = testOptions(true);
    o.lod.frustumCulling = o.lod.tfCulling = false;
    Renderer all(file, o);
    all.prepare(testCamera(8), fr, st);
    double maxErr = 0;
    for (int k = 0; k < 65; k += 3)
      for (int j = 0; j < 65; j += 5)
        for (int i = 0; i < 65; i += 7) {
          const float p[3] = {-1.f + 2.f * i / 64.f, -1.f + 2.f * j / 64.f, -1.f + 2.f * k / 64.f};
          float v, g[3];
          ASSERT_TRUE(ModelSampler{}.sample<false>(fr.view, p, v, g));
          maxErr = std::max(maxErr, std::abs(double(v) - ml.valueT<double>(p[0], p[1], p[2])));
        }
    std::printf("%s grid max error %.2e\n", modeName(mode), maxErr);
    EXPECT_LT(maxErr, mode == EncodingMode::Downsampled ? 1e-5 : 2e-2);
  }
}

TEST(Renderer, ShadingOffComputesNoGradientAndDiffersFromShaded) {
  auto file = afam_test::encodeMl(65, EncodingMode::Adaptive, 3, 4, 1e-3);
  RenderOptions o = testOptions();
  o.shading = false;
  Renderer flat(file, o);
  Renderer lit(file, testOptions());
  FrameStats s;
  const ImageRGBA a = flat.renderFrame(testCamera(32), s), b = lit.renderFrame(testCamera(32), s);
  EXPECT_LT(psnrOf(a, b), 40.0);
}

TEST(Renderer, GradientWithValueGivesTheSameImageWithFewerEvaluations) {
  // Degree 2 (closed-form basis) and degree 4 (Cox-de Boor): one value+gradient evaluation per
  // sample must give the image of "value first, gradient again where visible", bit for bit.
  for (int degree : {2, 4}) {
    auto file = afam_test::encodeMl(65, EncodingMode::Adaptive, 3, 4, 1e-3, 0, degree);
    Renderer r(file, testOptions());
    PreparedFrame fr;
    FrameStats stats;
    r.prepare(testCamera(40), fr, stats);
    ASSERT_GT(fr.view.slotCount, 0);
    ImageRGBA together, separate;
    fr.view.gradientWithValue = 1;
    renderCpu(fr.view, together, 2);
    fr.view.gradientWithValue = 0;
    renderCpu(fr.view, separate, 2);
    ASSERT_EQ(together.rgba.size(), separate.rgba.size());
    size_t differ = 0;
    float alpha = 0.f;
    for (size_t i = 0; i < together.rgba.size(); ++i) {
      differ += together.rgba[i] != separate.rgba[i];
      alpha += together.rgba[i];
    }
    EXPECT_EQ(differ, 0u) << "degree " << degree;
    EXPECT_GT(alpha, 1.f) << "degree " << degree;  // something was drawn
    // Count the evaluations: one per sample with gradientWithValue, more without.
    auto countSamples = [&](int32_t gradientWithValue) {
      fr.view.gradientWithValue = gradientWithValue;
      unsigned total = 0;
      for (int y = 0; y < 40; y += 3)
        for (int x = 0; x < 40; x += 3)
          castRayWith<true>(fr.view, SampleCounter<ModelSampler>{{}, &total}, x, y);
      return total;
    };
    const unsigned together1 = countSamples(1), separate1 = countSamples(0);
    EXPECT_EQ(together1, separate1) << "the counter counts ray samples either way";
    EXPECT_GT(together1, 100u);
  }
}

TEST(Renderer, CameraInsideTheVolumeSeesSomething) {
  auto file = afam_test::encodeMl(65, EncodingMode::Adaptive, 3, 4, 1e-3);
  Renderer r(file, testOptions());
  FrameStats st;
  const ImageRGBA img = r.renderFrame(Camera::fromPose({0.6, 50, 20}, 32, 32), st);
  double alpha = 0;
  for (size_t i = 3; i < img.rgba.size(); i += 4) alpha += img.rgba[i];
  EXPECT_GT(alpha, 0.0);
}

TEST(ImageMetrics, KnownValuesAndPngRoundTrip) {
  ImageRGB8 a;
  a.width = 32;
  a.height = 24;
  a.rgb.resize(32 * 24 * 3);
  for (size_t i = 0; i < a.rgb.size(); ++i) a.rgb[i] = uint8_t((i * 7) % 251);
  ImageRGB8 b = a;
  const ImageErrors same = compare(a, b);
  EXPECT_EQ(same.mse, 0.0);
  EXPECT_NEAR(same.ssim, 1.0, 1e-12);
  for (auto& v : b.rgb) v = uint8_t(std::min(255, v + 10));
  const ImageErrors e = compare(b, a);
  EXPECT_GT(e.mse, 0);
  EXPECT_NEAR(e.psnr, 10 * std::log10(255.0 * 255.0 / e.mse), 1e-9);
  EXPECT_LT(e.ssim, 1.0);
  const std::string path = afam_test::scratchPath("image.png");
  writePng(path, a);
  const ImageRGB8 r = readPng(path);
  EXPECT_EQ(r.width, a.width);
  EXPECT_EQ(r.height, a.height);
  EXPECT_EQ(r.rgb, a.rgb);
  std::remove(path.c_str());
  EXPECT_THROW(readPng("/nonexistent.png"), IoError);
}

TEST(Renderer, MaxDistanceHidesTheVolumeBehindOpaqueGeometry) {
  // Per-pixel ray limits as the VTK mapper passes them from the z-buffer: +inf changes nothing,
  // a limit in front of the volume empties the pixel, a limit through the middle keeps only the
  // front part (less opacity than the full ray), and the limited image is otherwise unchanged.
  auto file = afam_test::encodeMl(65, EncodingMode::Adaptive, 3, 4, 1e-3);
  const int n = 32;
  const Camera cam = testCamera(n);
  Renderer r(file, testOptions());
  FrameStats st;
  const ImageRGBA full = r.renderFrame(cam, st);
  std::vector<float> limit(size_t(n) * n, INFINITY);
  EXPECT_EQ(r.renderFrame(cam, st, limit.data()).rgba, full.rgba);
  const double eyeToCenter = std::sqrt(1.1 * 1.1 + 1.3 * 1.3 + 0.9 * 0.9);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      float& t = limit[size_t(y) * n + size_t(x)];
      if (x < n / 2)
        t = y < n / 2 ? 0.25f
                      : float(eyeToCenter);  // in front (box is >= 0.32 away) / through the middle
    }
  const ImageRGBA cut = r.renderFrame(cam, st, limit.data());
  double hiddenAlpha = 0, middleAlpha = 0, middleFullAlpha = 0, rightDiff = 0;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const size_t i = (size_t(y) * n + size_t(x)) * 4;
      if (x >= n / 2) {
        for (int k = 0; k < 4; ++k)
          rightDiff += std::abs(cut.rgba[i + size_t(k)] - full.rgba[i + size_t(k)]);
      } else if (y < n / 2) {
        hiddenAlpha += cut.rgba[i + 3];
      } else {
        EXPECT_LE(cut.rgba[i + 3], full.rgba[i + 3] + 1e-6f);
        middleAlpha += cut.rgba[i + 3];
        middleFullAlpha += full.rgba[i + 3];
      }
    }
  EXPECT_EQ(hiddenAlpha, 0.0);
  EXPECT_EQ(rightDiff, 0.0);
  EXPECT_GT(middleFullAlpha, 1.0);  // the volume is visible there at all
  EXPECT_GT(middleAlpha, 0.05 * middleFullAlpha);
  EXPECT_LT(middleAlpha, 0.9 * middleFullAlpha);
}

TEST(Renderer, MaximumIntensityProjectionMatchesTheAnalyticOneAndCullsNothingByOpacity) {
  auto file = afam_test::encodeMl(65, EncodingMode::Adaptive, 3, 4, 1e-3);
  // A table that is transparent below the middle of the range: composite frames cull blocks by
  // it, projections must not (a transparent block can hold a ray's extreme value).
  TransferFunction tf;
  tf.colors = {{0.0, 0.1, 0.2, 0.9}, {1.0, 1.0, 0.8, 0.1}};
  tf.opacities = {{0.0, 0.0}, {0.55, 0.0}, {1.0, 0.9}};
  RenderOptions o = testOptions(true);
  o.hasTransferFunction = true;
  o.transferFunction = tf;
  const Camera c = testCamera();
  FrameStats composite, mip;
  {
    Renderer r(file, o);
    (void)r.renderFrame(c, composite);
  }
  o.blendMode = kBlendMaximum;
  Renderer r(file, o);
  const ImageRGBA img = r.renderFrame(c, mip);
  const ImageRGBA gt = groundTruth(r, c);
  const double p = psnrOf(img, gt);
  std::printf("mip psnr=%.2f; tf-culled blocks: composite %lld, mip %lld\n", p,
              (long long)composite.culled.tfBlocks, (long long)mip.culled.tfBlocks);
  EXPECT_GT(composite.culled.tfBlocks, 0);
  EXPECT_EQ(mip.culled.tfBlocks, 0);
  EXPECT_GT(p, 35.0);
  double alpha = 0;
  for (size_t i = 3; i < img.rgba.size(); i += 4) alpha += img.rgba[i];
  EXPECT_GT(alpha, 0.2 * c.width * c.height);  // the projection covers much of the view
  o.blendMode = 7;
  EXPECT_THROW(Renderer(file, o), InvalidArgument);
}

namespace {
/// A caster that casts on the CPU and keeps what each frame handed it (the GPU caster's seat).
class RecordingCaster : public CpuCaster {
 public:
  RecordingCaster() : CpuCaster(2) {}
  CastResult cast(const PreparedFrame& frame, const FrameTargets& targets,
                  ImageRGBA& image) override {
    seen.push_back(targets);
    CastResult result = CpuCaster::cast(frame, targets, image);
    result.messages.push_back("frame " + std::to_string(seen.size()));
    return result;
  }
  std::vector<FrameTargets> seen;
};
}  // namespace

TEST(Renderer, TargetsGoWithEachFrameAndTheCastersResultIntoItsStats) {
  // Where a frame's image goes is that frame's argument: a device buffer given to one frame is
  // not seen by the next, and the host limits reach the caster as given. The caster's result
  // (here its messages) lands in the frame's stats; the CPU's caster gives the same image.
  auto file = afam_test::encodeMl(33, EncodingMode::Adaptive, 2, 4, 1e-3);
  const int n = 24;
  const Camera cam = testCamera(n);
  Renderer cpu(file, testOptions()), recorded(file, testOptions());
  EXPECT_FALSE(cpu.caster().castsOnGpu());
  EXPECT_EQ(cpu.caster().deviceStream(), nullptr);
  auto owned = std::make_unique<RecordingCaster>();
  RecordingCaster& caster = *owned;
  recorded.setCaster(std::move(owned));
  FrameStats st;
  const ImageRGBA reference = cpu.renderFrame(cam, st);
  EXPECT_FALSE(st.cast.onGpu);
  EXPECT_FALSE(st.cast.imageOnDevice);
  EXPECT_EQ(st.cast.modelsUploaded, -1);
  EXPECT_EQ(st.cast.depthLimitedPixels, -1);
  EXPECT_TRUE(st.cast.messages.empty());

  float notTouched = 0;  // a CPU caster never writes a device buffer
  std::vector<float> limit(size_t(n) * n, INFINITY);
  FrameTargets targets;
  targets.deviceRgba = &notTouched;
  targets.deviceRgbaFloats = 1;
  targets.maxDistance = limit.data();
  const ImageRGBA first = recorded.renderFrame(cam, st, targets);
  EXPECT_EQ(first.rgba, reference.rgba);
  ASSERT_EQ(st.cast.messages.size(), 1u);
  EXPECT_EQ(st.cast.messages[0], "frame 1");
  const ImageRGBA second = recorded.renderFrame(cam, st);
  EXPECT_EQ(second.rgba, reference.rgba);
  ASSERT_EQ(st.cast.messages.size(), 1u);
  EXPECT_EQ(st.cast.messages[0], "frame 2");
  ASSERT_EQ(caster.seen.size(), 2u);
  EXPECT_EQ(caster.seen[0].deviceRgba, &notTouched);
  EXPECT_EQ(caster.seen[0].maxDistance, limit.data());
  EXPECT_EQ(caster.seen[1].deviceRgba, nullptr);  // nothing carried into the next frame
  EXPECT_EQ(caster.seen[1].deviceRgbaFloats, 0u);
  EXPECT_EQ(caster.seen[1].maxDistance, nullptr);
  EXPECT_EQ(notTouched, 0.f);

  recorded.setCaster(nullptr);  // back to the CPU's
  EXPECT_EQ(recorded.caster().description(), "CPU");
  EXPECT_EQ(recorded.renderFrame(cam, st).rgba, reference.rgba);
  EXPECT_TRUE(st.cast.messages.empty());
}

TEST(Renderer, AFrameWaitsNoLongerThanItsMissBudgetAndTheStillFrameIsExact) {
  const auto file = afam_test::encodeMl(65, EncodingMode::Adaptive, 3, 8, 1e-3);
  RenderOptions o = testOptions();
  o.storageMBps = 0.5;  // slow storage: the finest level's misses take about a second
  o.loadThreads = 4;
  Renderer r(file, o);
  const Camera c = testCamera(48);
  FrameSettings coarse = r.settings(), fine = r.settings();
  coarse.lod.forceLevel = 0;
  fine.lod.forceLevel = file->partition().levels() - 1;
  FrameStats st;
  r.renderFrame(c, coarse, st);  // the coarsest level is resident from here on
  EXPECT_EQ(st.standInBlocks, 0);

  fine.missBudgetMs = 20;
  const auto t0 = std::chrono::steady_clock::now();
  r.renderFrame(c, fine, st);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_GT(st.standInBlocks, 0) << "finest blocks still loading are drawn from level 0";
  EXPECT_LT(st.cachingMs, 300) << "the frame waited " << st.cachingMs << " ms for its misses";
  std::printf("[miss budget] stand-ins %lld, caching %.1f ms, frame %.1f ms\n",
              static_cast<long long>(st.standInBlocks), st.cachingMs, ms);
  uint64_t fineBytes = st.bytesRead;

  fine.missBudgetMs = -1;  // the still frame: waits for every block
  const ImageRGBA still = r.renderFrame(c, fine, st);
  fineBytes += st.bytesRead;
  EXPECT_EQ(st.standInBlocks, 0);
  // Every read goes through the 0.5 MB/s cap: the finest level took far longer to arrive than
  // the budgeted frame waited (the test discriminates).
  EXPECT_GT(double(fineBytes) / 0.5e6 * 1e3, 600.0) << fineBytes << " bytes";
  RenderOptions exact = testOptions();
  Renderer fresh(file, exact);
  FrameStats st2;
  const ImageRGBA want = fresh.renderFrame(c, fine, st2);
  ASSERT_EQ(still.rgba.size(), want.rgba.size());
  for (size_t i = 0; i < want.rgba.size(); ++i) ASSERT_EQ(still.rgba[i], want.rgba[i]) << i;
}

TEST(Renderer, AnUnusableMissBudgetIsRefused) {
  const auto file = afam_test::encodeMl(33, EncodingMode::Adaptive, 2, 4, 1e-3);
  Renderer r(file, testOptions());
  for (const double absurd : {std::nan(""), HUGE_VAL, 1e20, kMaxMissBudgetMs * 1.01}) {
    SCOPED_TRACE(absurd);
    FrameSettings s = r.settings();
    s.missBudgetMs = absurd;
    EXPECT_THROW(r.setFrameSettings(s), InvalidArgument);
    std::vector<std::string> warnings;
    const FrameSettings kept = acceptFrameSettings(s, r.settings(), warnings);
    EXPECT_EQ(kept.missBudgetMs, -1);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("miss budget"), std::string::npos) << warnings[0];
  }
  // An hour is a budget; so is -infinity (no budget: every block waited for).
  for (const double usable : {kMaxMissBudgetMs, 0.0, -HUGE_VAL}) {
    FrameSettings s = r.settings();
    s.missBudgetMs = usable;
    EXPECT_NO_THROW(r.setFrameSettings(s)) << usable;
  }
}

namespace {

/// Reads the cached models as a GPU caster does; records what the frame held.
class ModelReadingCaster : public FrameCaster {
 public:
  CastResult cast(const PreparedFrame& frame, const FrameTargets& targets,
                  ImageRGBA& image) override {
    poolWasEmpty = frame.pool.empty() && frame.view.pool == nullptr;
    slots = frame.view.slotCount;
    for (size_t s = 0; s < frame.slotHost.size(); ++s)
      sharesCachedModels = sharesCachedModels && frame.slotHost[s] == frame.models[s]->data();
    return CpuCaster(2).cast(frame, targets, image);
  }
  bool castsOnGpu() const override { return false; }
  std::string description() const override { return "test"; }
  bool readsHostPool() const override { return false; }
  bool poolWasEmpty = false, sharesCachedModels = true;
  int32_t slots = 0;
};

}  // namespace

TEST(Renderer, ACasterThatReadsTheCachedModelsGetsNoCopyOfThemAndTheSameImage) {
  const auto file = afam_test::encodeMl(33, EncodingMode::Adaptive, 2, 4, 1e-3);
  const Camera c = testCamera(40);
  Renderer copying(file, testOptions());
  FrameStats st;
  const ImageRGBA want = copying.renderFrame(c, st);
  Renderer referencing(file, testOptions());
  auto caster = std::make_unique<ModelReadingCaster>();
  ModelReadingCaster* seen = caster.get();
  referencing.setCaster(std::move(caster));
  const ImageRGBA got = referencing.renderFrame(c, st);
  EXPECT_TRUE(seen->poolWasEmpty);
  EXPECT_TRUE(seen->sharesCachedModels);
  EXPECT_GT(seen->slots, 0);
  EXPECT_GT(st.poolBytes, 0u) << "the models' bytes are still counted";
  EXPECT_EQ(got.rgba, want.rgba);
}
