// SPDX-License-Identifier: BSD-3-Clause
// Missing samples on the GPU: the masked scene (Testing/Core/masked_scene.hpp: masked blocks with
// their mask words in the pool, empty blocks culled or drawn) cast by the CUDA kernels equals the
// CPU reference, in every float mode, degree-specialised or not, composite and projections; rays
// through missing samples only stay background, or take the NaN colour. Skipped, with the reason,
// where no GPU is usable.
#include <gtest/gtest.h>

#include <cstdio>

#include "../Core/masked_scene.hpp"
#include "afam/cuda/common/gpu_error.hpp"
#include "afam/cuda/render/gpu_renderer.hpp"
#include "afam/render/cpu_raycaster.hpp"
#include "gpu_scene.hpp"

namespace afam::gputest {
namespace {

struct MissingCase {
  const char* name;
  afam_test::MaskedSceneOptions options;
  int blendMode = kBlendComposite;
};

std::vector<MissingCase> missingCases() {
  std::vector<MissingCase> out;
  out.push_back({"default shaded", {}});
  MissingCase unshaded{"default unshaded", {}};
  unshaded.options.shaded = false;
  out.push_back(unshaded);
  MissingCase drawn{"NaN opacity 1", {}};
  drawn.options.drawMissing = true;
  drawn.options.nanOpacity = 1.f;
  out.push_back(drawn);
  MissingCase partial{"NaN opacity 0.05", {}};
  partial.options.drawMissing = true;
  partial.options.nanOpacity = 0.05f;
  out.push_back(partial);
  MissingCase naive{"fill 0 (halo)", {}};
  naive.options.smoothFill = false;
  out.push_back(naive);
  MissingCase maximum{"maximum, NaN opacity 0.6", {}};
  maximum.options.drawMissing = true;
  maximum.options.nanOpacity = 0.6f;
  maximum.blendMode = kBlendMaximum;
  out.push_back(maximum);
  return out;
}

TEST(GpuMissing, MaskedSceneMatchesCpuAndMissingRaysAreBackgroundOrNanColour) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  for (const MissingCase& c : missingCases()) {
    // A renderer per scene: the scenes key their blocks alike, and a pool keeps models by key.
    GpuRenderer gpu(size_t(64) << 20);
    gpu.setPoisonOutput(true);
    afam_test::MaskedScene s;
    buildMaskedScene(afam_test::maskedSceneCamera(200, 160), c.options, s);
    s.view.blendMode = c.blendMode;
    ImageRGBA cpu;
    renderCpu(s.view, cpu, 0);
    const std::vector<size_t> missing = afam_test::missingOnlyPixels(s.view);
    ASSERT_GT(missing.size(), 3000u);
    for (GpuFloatMode mode : {GpuFloatMode::Exact, GpuFloatMode::Fast}) {
      for (bool specialise : {true, false}) {
        gpu.setFloatMode(mode);
        gpu.setDegreeSpecialisation(specialise);
        std::vector<float> image(cpu.rgba.size(), 0.f);
        gpu.render(s.view, s.keys.data(), image.data());
        const ImageDiff d = compareImages(cpu.rgba, image);
        std::printf(
            "[gpu-missing] %s, %s, %s: max |diff| %d/255, %lld of %lld pixels differ, unwritten "
            "%lld\n",
            c.name, mode == GpuFloatMode::Exact ? "exact" : "fast", specialise ? "p=2" : "p=any",
            d.maxAbs8, (long long)d.differing, (long long)d.pixels, (long long)d.nonFinite);
        EXPECT_EQ(d.nonFinite, 0);
        EXPECT_LE(d.maxAbs8, 2);
        // Known alphas there: 0 (not drawn), the NaN opacity once (projections) or 1 (opaque);
        // a partial opacity composited over many samples: the CPU's.
        const afam_test::MaskedSceneOptions& o = c.options;
        for (size_t p : missing) {
          const float alpha = !o.drawMissing                   ? 0.f
                              : c.blendMode != kBlendComposite ? o.nanOpacity
                              : o.nanOpacity >= 1.f            ? 1.f
                                                               : cpu.rgba[p * 4 + 3];
          ASSERT_NEAR(image[p * 4 + 3], alpha, 1e-5f) << c.name << ", pixel " << p;
        }
      }
    }
  }
}

}  // namespace
}  // namespace afam::gputest
