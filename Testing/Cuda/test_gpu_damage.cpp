// SPDX-License-Identifier: BSD-3-Clause
// A file with damaged micro-models cast on the GPU (Renderer + GpuCaster) gives the CPU's
// image: the stand-in models are chosen in Core while the frame is prepared, for both casters.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "../Core/damaged_copy.hpp"
#include "../Core/render_test_util.hpp"
#include "afam/cuda/common/gpu_error.hpp"
#include "afam/cuda/render/gpu_caster.hpp"
#include "afam/render/renderer.hpp"

namespace afam {
namespace {

TEST(GpuDamage, DamagedFileCastOnTheGpuMatchesTheCpu) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  auto intact = afam_test::encodeMl(65, EncodingMode::Adaptive, 3, 4, 1e-3);
  // Two siblings drawn by their parent, a block left empty, a damaged coarsest block.
  const std::vector<int64_t> damaged = {
      intact->entryIndex(0, {0, 0, 0}), intact->entryIndex(1, {1, 1, 1}),
      intact->entryIndex(2, {0, 0, 0}), intact->entryIndex(2, {1, 0, 0}),
      intact->entryIndex(2, {2, 2, 2})};
  auto file = afam_test::damagedCopy(*intact, afam_test::tempPath("gpu_damaged"), damaged);
  for (int level : {0, 1, 2}) {
    RenderOptions o;
    o.sampleDistance = 0.01f;
    o.cache = CacheBudget{};
    o.lod.forceLevel = level;
    Renderer cpu(file, o), gpu(file, o);
    std::unique_ptr<FrameCaster> caster =
        makeGpuCaster(size_t(256) << 20, o.threads,
                      [](const std::string& m) { std::printf("gpu: %s\n", m.c_str()); });
    ASSERT_TRUE(caster);
    gpu.setCaster(std::move(caster));
    const Camera c = Camera::lookAt({1.6, 1.9, 1.3}, {0, 0, 0}, {0, 0, 1}, 60, 128, 128);
    FrameStats sc, sg;
    const ImageRGBA ic = cpu.renderFrame(c, sc), ig = gpu.renderFrame(c, sg);
    EXPECT_TRUE(sg.cast.onGpu);
    double worst = 0, alpha = 0;
    for (size_t i = 0; i < ic.rgba.size(); ++i) {
      worst = std::max(worst, double(std::fabs(ic.rgba[i] - ig.rgba[i])));
      if (i % 4 == 3) alpha += ic.rgba[i];
    }
    std::printf(
        "[gpu-damage] level %d: slots %lld, damaged %lld, reports %zu, max |gpu - cpu| %.5f, alpha "
        "%.1f\n",
        level, (long long)sg.slots, (long long)sg.damagedBlocks, sg.damageReports.size(), worst,
        alpha);
    EXPECT_EQ(sg.slots, sc.slots);
    EXPECT_EQ(sg.damagedBlocks, sc.damagedBlocks);
    EXPECT_GE(sg.damagedBlocks, 1);
    EXPECT_EQ(sg.damageReports.size(), sc.damageReports.size());
    EXPECT_GT(alpha, 100.0);
    EXPECT_LE(worst, 2.0 / 255.0);
  }
}

}  // namespace
}  // namespace afam
