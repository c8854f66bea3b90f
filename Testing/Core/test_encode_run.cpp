// SPDX-License-Identifier: BSD-3-Clause
// encodeRun: a run of steps in one file, coded in time. Blocks that did not change beyond the
// bound become references (no payload) within the key interval; every step decodes within the
// bound of its own samples; a run of unrelated steps stores every block; bad runs are refused.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/encode/encode_run.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/render/level_decode.hpp"
#include "moving_blob.hpp"
#include "scratch_dir.hpp"

using namespace afam;

namespace {

std::string scratch(const std::string& name) {
  return afam_test::scratchPath("afam_encode_run_" + name);  // removed with its folder at exit
}

const Index3 kDims{40, 36, 30};

std::vector<float> evolving(int k) { return afam_test::movingBlob(kDims, k); }

/// The RMSE of step s's finest level as a reader decodes it, against its samples.
double decodedRmse(const std::string& path, int64_t s, const std::vector<float>& truth) {
  auto f = AfamFile::open(path, s);
  std::vector<float> out(truth.size());
  decodeLevelBox(*f, f->header().levels - 1, {0, 0, 0}, {kDims[0] - 1, kDims[1] - 1, kDims[2] - 1},
                 out.data());
  double sum = 0;
  for (size_t i = 0; i < out.size(); ++i) sum += double(out[i] - truth[i]) * (out[i] - truth[i]);
  return std::sqrt(sum / double(out.size()));
}

}  // namespace

TEST(EncodeRun, UnchangedBlocksAreReferencesAndEveryStepMeetsTheBound) {
  afam_test::InMemoryRun series(kDims,
                                {evolving(0), evolving(1), evolving(2), evolving(3), evolving(4)});
  const std::vector<std::vector<float>>& data = series.data;
  std::vector<ArraySource>& sources = series.sources;
  const std::vector<VolumeSource*>& steps = series.steps;
  const EncoderOptions opt = afam_test::runTestOptions(4);
  RunOptions run;
  run.keyInterval = 3;
  run.times = {0, 0.5, 1, 1.5, 2};
  const std::string path = scratch("evolving.afam");
  const RunStats st = encodeRun(steps, opt, run, path);
  ASSERT_EQ(st.steps.size(), 5u);
  EXPECT_EQ(st.references[0], 0);
  auto f0 = AfamFile::open(path, 0);
  const int64_t blocks = int64_t(f0->entries().size());
  EXPECT_EQ(f0->stepCount(), 5);
  EXPECT_EQ(f0->stepTimes(), run.times);
  EXPECT_DOUBLE_EQ(f0->header().valueMin, st.valueMin) << "the run's range";
  for (int64_t s = 0; s < 5; ++s) {
    SCOPED_TRACE("step " + std::to_string(s));
    auto f = AfamFile::open(path, s);
    int64_t refs = 0;
    for (const ModelEntry& e : f->entries()) {
      refs += e.reference;
      EXPECT_LE(e.rmse, st.bound * (1 + 1e-6));
      EXPECT_LE(s - e.ownerStep, run.keyInterval - 1) << "the key interval holds";
    }
    EXPECT_EQ(refs, st.references[size_t(s)]);
    if (s > 0 && s % 3 != 0) {
      EXPECT_GT(refs, blocks / 3) << "most blocks do not change";
    }
    EXPECT_LE(decodedRmse(path, s, data[size_t(s)]), st.bound);
  }
  // Against one file per step: the run's payloads are a fraction of theirs (the indexes, 40
  // bytes a block and step, are the same in both).
  uint64_t separate = 0, inRun = 0;
  EncoderOptions absolute = opt;
  absolute.errorBound = st.bound;
  absolute.relativeBound = false;
  for (int k = 0; k < 5; ++k) {
    const std::string one = scratch("one.afam");
    separate += encodeVolume(sources[size_t(k)], absolute, one).payloadBytes;
    inRun += st.steps[size_t(k)].payloadBytes;
    std::remove(one.c_str());
  }
  EXPECT_LT(double(inRun), 0.6 * double(separate))
      << inRun << " payload bytes against " << separate << " in five files";
  std::remove(path.c_str());
}

TEST(EncodeRun, UnrelatedStepsStoreEveryBlockAndBadRunsAreRefused) {
  std::vector<std::vector<float>> data;
  for (int k = 0; k < 3; ++k) {
    std::vector<float> v(size_t(kDims[0] * kDims[1] * kDims[2]));
    std::mt19937 rng(unsigned(100 + k));
    std::uniform_real_distribution<float> u(0, 10);
    for (float& x : v) x = u(rng);
    data.push_back(std::move(v));
  }
  std::vector<ArraySource> sources;
  for (const auto& d : data) sources.emplace_back(d.data(), kDims);
  std::vector<VolumeSource*> steps{&sources[0], &sources[1], &sources[2]};
  EncoderOptions opt;
  opt.errorBound = 1e-2;
  opt.relativeBound = true;
  opt.levels = 1;
  opt.blocksPerAxis = 2;
  const std::string path = scratch("noise.afam");
  const RunStats st = encodeRun(steps, opt, RunOptions{}, path);
  for (int64_t r : st.references) EXPECT_EQ(r, 0);
  for (int64_t s = 0; s < 3; ++s) EXPECT_LE(decodedRmse(path, s, data[size_t(s)]), st.bound);
  std::remove(path.c_str());

  const std::vector<float> other(size_t(kDims[0] * kDims[1] * (kDims[2] - 1)), 1.0f);
  ArraySource smaller(other.data(), {kDims[0], kDims[1], kDims[2] - 1});
  std::vector<VolumeSource*> mixed{&sources[0], &smaller};
  try {
    encodeRun(mixed, opt, RunOptions{}, path);
    ADD_FAILURE() << "steps of two grids were encoded";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("step 1"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("dims 40x36x29 differ"), std::string::npos) << e.what();
  }
  RunOptions backwards;
  backwards.times = {0, 2, 1};
  EXPECT_THROW(encodeRun(steps, opt, backwards, path), InvalidArgument);
  EXPECT_NE(::access(path.c_str(), F_OK), 0) << "nothing written";
}

// A block that refers to the same model for several steps is measured against that model's
// decoded samples kept from the step after it was written: decoded once, not at every step.
TEST(EncodeRun, AModelReferredToForManyStepsIsDecodedOnce) {
  afam_test::InMemoryRun series(
      kDims, {evolving(0), evolving(0), evolving(0), evolving(1), evolving(1), evolving(1)});
  RunOptions run;
  run.keyInterval = 16;
  const std::string path = scratch("kept.afam");
  const RunStats st = encodeRun(series.steps, afam_test::runTestOptions(4), run, path);
  ASSERT_EQ(st.decodedBefore.size(), 6u);
  const int64_t blocks = st.steps[0].blocks;
  EXPECT_EQ(st.decodedBefore[0], 0) << "no step before";
  EXPECT_EQ(st.decodedBefore[1], blocks) << "every model of the first step, once";
  EXPECT_EQ(st.references[1], blocks);
  EXPECT_EQ(st.references[2], blocks);
  EXPECT_EQ(st.decodedBefore[2], 0) << "the same models as at step 1: kept";
  const int64_t changed = blocks - st.references[3];
  EXPECT_GT(changed, 0) << "the blob moved at step 3";
  EXPECT_LT(changed, blocks);
  EXPECT_EQ(st.decodedBefore[3], 0) << "the unchanged blocks' models kept since step 1";
  EXPECT_EQ(st.decodedBefore[4], changed) << "the models written at step 3, each once";
  EXPECT_EQ(st.references[4], blocks);
  EXPECT_EQ(st.decodedBefore[5], 0);
  for (int64_t s = 0; s < 6; ++s)
    EXPECT_LE(decodedRmse(path, s, series.data[size_t(s)]), st.bound) << "step " << s;
  std::remove(path.c_str());
}
