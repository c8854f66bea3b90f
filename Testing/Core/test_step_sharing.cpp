// SPDX-License-Identifier: BSD-3-Clause
// Playing a run: a Renderer moved to another step (setStep) keeps what the steps share (the
// models a step refers to) and loads only what changed, draws the step exactly as a renderer
// opened on it, and with setNextStep loads the next step's models of the view while this step is
// shown, so that the next frame misses nothing. A jump to a step draws exactly as the step's
// own file (afam extract). The cache refuses a file of another run.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/encode/encode_run.hpp"
#include "afam/format/step_extract.hpp"
#include "afam/render/renderer.hpp"
#include "moving_blob.hpp"
#include "scratch_dir.hpp"

using namespace afam;

namespace {

const Index3 kDims{40, 36, 30};

std::vector<float> step(int k) { return afam_test::movingBlob(kDims, k, 4.0); }

std::string encodeRunOfThree() {
  const std::string path = afam_test::scratchPath("step_sharing.afam");
  afam_test::InMemoryRun run(kDims, {step(0), step(1), step(2)});
  encodeRun(run.steps, afam_test::runTestOptions(4), RunOptions{}, path);
  return path;
}

RendererResources resources() {
  RendererResources r;
  r.threads = 2;
  r.loadThreads = 2;
  r.cache = CacheBudget{0, 0};
  return r;
}

/// The finest level everywhere (every block of the view drawn from its own model), no TF culling.
FrameSettings finest() {
  FrameSettings f;
  f.lod.forceLevel = 1;
  f.lod.tfCulling = false;
  return f;
}

const Camera kCamera = Camera::lookAt({1.6, 1.4, 1.1}, {0, 0, 0}, {0, 0, 1}, 50, 40, 40);

/// Entries of `f`'s frame whose model is not one of `before`'s frame.
int64_t newModels(const PreparedFrame& now, const PreparedFrame& before) {
  int64_t n = 0;
  for (const uint64_t k : now.keys)
    n += std::find(before.keys.begin(), before.keys.end(), k) == before.keys.end();
  return n;
}

}  // namespace

TEST(StepSharing, AnotherStepReadsOnlyWhatChangedAndDrawsAsARendererOpenedOnIt) {
  const std::string path = encodeRunOfThree();
  Renderer r(AfamFile::open(path, 0), resources(), finest());
  FrameStats s0, s1;
  const ImageRGBA i0 = r.renderFrame(kCamera, s0);
  PreparedFrame f0;
  FrameStats ignored;
  r.prepare(kCamera, f0, ignored);
  ASSERT_GT(s0.misses, 10u);
  r.setStep(AfamFile::open(path, 1));
  const ImageRGBA i1 = r.renderFrame(kCamera, s1);
  Renderer fresh(AfamFile::open(path, 1), resources(), finest());
  FrameStats sf;
  PreparedFrame f1;
  fresh.prepare(kCamera, f1, ignored);
  const int64_t changed = newModels(f1, f0);
  EXPECT_GT(changed, 0) << "the blob moved";
  EXPECT_LT(changed, int64_t(f1.keys.size()) / 2) << "most blocks are references";
  EXPECT_EQ(int64_t(s1.misses), changed) << "only the models step 1 does not share are read";
  EXPECT_EQ(fresh.renderFrame(kCamera, sf).rgba, i1.rgba) << "step 1 drawn as it is";
  EXPECT_NE(i0.rgba, i1.rgba);
  std::remove(path.c_str());
}

TEST(StepSharing, TheNextStepIsLoadedWhileThisOneIsShown) {
  const std::string path = encodeRunOfThree();
  Renderer r(AfamFile::open(path, 1), resources(), finest());
  r.setNextStep(AfamFile::open(path, 2));
  FrameStats s1, s2;
  r.renderFrame(kCamera, s1);
  ASSERT_TRUE(r.loader().waitIdle(std::chrono::steady_clock::now() + std::chrono::seconds(20)));
  EXPECT_GT(r.loader().stats().stepLoads, 0u);
  r.setStep(AfamFile::open(path, 2));
  r.setNextStep(nullptr);
  const ImageRGBA i2 = r.renderFrame(kCamera, s2);
  EXPECT_EQ(s2.misses, 0u) << "step 2's models of the view were loaded during step 1";
  Renderer fresh(AfamFile::open(path, 2), resources(), finest());
  FrameStats sf;
  EXPECT_EQ(fresh.renderFrame(kCamera, sf).rgba, i2.rgba);
  std::remove(path.c_str());
}

TEST(StepSharing, AResidualIsDecodedFromTheResidentModelBeforeItAsFromItsWholeChain) {
  const std::string path = afam_test::scratchPath("step_sharing_residuals.afam");
  {
    std::vector<std::vector<float>> values;
    for (int k = 0; k < 6; ++k) values.push_back(afam_test::driftingWaves(kDims, k));
    afam_test::InMemoryRun run(kDims, std::move(values));
    const RunStats st = encodeRun(run.steps, afam_test::runTestOptions(3), RunOptions{}, path);
    ASSERT_GT(st.residuals[5], 0);
  }
  Renderer r(AfamFile::open(path, 0), resources(), finest());
  FrameStats st;
  r.renderFrame(kCamera, st);
  for (int64_t s = 1; s < 6; ++s) {
    SCOPED_TRACE("step " + std::to_string(s));
    r.setStep(AfamFile::open(path, s));
    const ImageRGBA played = r.renderFrame(kCamera, st);
    Renderer fresh(AfamFile::open(path, s), resources(), finest());  // whole chains
    FrameStats sf;
    EXPECT_EQ(fresh.renderFrame(kCamera, sf).rgba, played.rgba);
    EXPECT_EQ(fresh.cache().stats().residualsOnResident, 0u);
  }
  EXPECT_GT(r.cache().stats().residualsOnResident, 20u) << "one payload a residual while playing";
  std::remove(path.c_str());
}

TEST(StepSharing, AJumpToAStepDrawsAsAFileOfThatStepAlone) {
  const std::string path = afam_test::scratchPath("step_sharing_jump.afam");
  const std::string alone = afam_test::scratchPath("step_sharing_jump_step4.afam");
  {
    std::vector<std::vector<float>> values;
    for (int k = 0; k < 6; ++k) {
      std::vector<float> v = afam_test::driftingWaves(kDims, k);
      const std::vector<float> blob = step(k);
      for (size_t i = 0; i < v.size(); ++i) v[i] += blob[i];
      values.push_back(std::move(v));
    }
    afam_test::InMemoryRun run(kDims, std::move(values));
    RunOptions options;
    options.keyInterval = 8;
    const RunStats st = encodeRun(run.steps, afam_test::runTestOptions(3), options, path);
    ASSERT_GT(st.residuals[4], 0);
    ASSERT_GT(st.references[4], 0);
  }
  const ExtractStats ex = extractStep(path, 4, alone);
  EXPECT_GT(ex.resolved, 0) << "residual chains stored as what they decode to";
  EXPECT_GT(ex.copied, 0) << "the others keep their stored bytes";
  auto one = AfamFile::open(alone);
  EXPECT_EQ(one->version(), 2u);
  EXPECT_EQ(one->stepCount(), 1);
  auto four = AfamFile::open(path, 4);
  ASSERT_EQ(one->entries().size(), four->entries().size());
  for (size_t i = 0; i < one->entries().size(); ++i)
    ASSERT_EQ(one->readPayload(int64_t(i)), four->readPayload(int64_t(i))) << "model " << i;
  // The run played from step 0, then a jump to step 4 (past the residuals in between): every
  // level drawn exactly as the file of step 4 alone draws it.
  for (int level : {0, 1}) {
    SCOPED_TRACE("level " + std::to_string(level));
    FrameSettings settings = finest();
    settings.lod.forceLevel = level;
    Renderer played(AfamFile::open(path, 0), resources(), settings);
    FrameStats st;
    played.renderFrame(kCamera, st);
    played.setStep(AfamFile::open(path, 1));
    played.renderFrame(kCamera, st);
    played.setStep(AfamFile::open(path, 4));
    const ImageRGBA jumped = played.renderFrame(kCamera, st);
    Renderer fresh(AfamFile::open(alone), resources(), settings);
    EXPECT_EQ(fresh.renderFrame(kCamera, st).rgba, jumped.rgba) << "0/255";
  }
  std::remove(path.c_str());
  std::remove(alone.c_str());
}

TEST(StepSharing, AFileOfAnotherRunIsRefused) {
  const std::string path = encodeRunOfThree();
  const std::string other = afam_test::scratchPath("step_sharing_other.afam");
  {
    std::vector<float> d = step(0);
    ArraySource src(d.data(), kDims);
    encodeVolume(src, afam_test::runTestOptions(4), other);
  }
  Renderer r(AfamFile::open(path, 0), resources(), finest());
  EXPECT_THROW(r.setStep(AfamFile::open(other)), InvalidArgument);
  EXPECT_THROW(r.setNextStep(AfamFile::open(other)), InvalidArgument);
  EXPECT_EQ(r.file().step(), 0) << "nothing changed";
  std::remove(path.c_str());
  std::remove(other.c_str());
}
