// SPDX-License-Identifier: BSD-3-Clause
// PipelineRun, the time-step state machine of ParaView's encoding filter: a run starts at its
// first step, asks for the steps in order and writes the file RunEncoder writes, byte for byte;
// progress runs across the steps; a step of another grid, a cancel or a call out of order leaves
// no file; a finished run stays current until its times change.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/encode/encode_run.hpp"
#include "afam/encode/pipeline_run.hpp"
#include "afam/format/afam_file.hpp"
#include "moving_blob.hpp"
#include "scratch_dir.hpp"

using namespace afam;

namespace {

const Index3 kDims{30, 26, 22};
const std::vector<double> kTimes{0.5, 1.0, 2.5};
const double kUnknownTime = std::numeric_limits<double>::quiet_NaN();

/// A folder of its own for each test (removed with the process's scratch folder).
std::string scratchDir(const std::string& name) {
  const std::string dir = afam_test::scratchPath("pipeline_run_" + name);
  std::filesystem::create_directories(dir);
  return dir;
}

size_t filesIn(const std::string& dir) {
  return static_cast<size_t>(std::distance(std::filesystem::directory_iterator(dir), {}));
}

std::string fileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

std::vector<std::vector<float>> waves(size_t count) {
  std::vector<std::vector<float>> out;
  for (size_t k = 0; k < count; ++k) out.push_back(afam_test::driftingWaves(kDims, int(k)));
  return out;
}

EncoderOptions options() {
  EncoderOptions opt = afam_test::runTestOptions(3);
  opt.threads = 1;
  return opt;
}

/// A run started on kTimes, into `path`.
void startRun(PipelineRun& run, const std::string& path, const EncoderOptions& opt = options()) {
  run.setTimes(kTimes);
  ASSERT_TRUE(run.readyToStart(kUnknownTime));
  run.start(path, opt);
}

}  // namespace

TEST(PipelineRun, AsksForTheStepsInOrderAndWritesRunEncodersFile) {
  const std::string dir = scratchDir("order/");
  afam_test::InMemoryRun series(kDims, waves(kTimes.size()));
  PipelineRun run;
  startRun(run, dir + "piped.afam");
  for (size_t k = 0; k < kTimes.size(); ++k) {
    EXPECT_EQ(run.stepToRead(), k);
    EXPECT_FALSE(run.complete());
    run.addStep(*series.steps[k]);
  }
  EXPECT_TRUE(run.complete());
  EXPECT_FALSE(std::filesystem::exists(dir + "piped.afam"));  // nothing before the commit
  const RunStats stats = run.commit(RunOrigin{7, 42});
  EXPECT_EQ(stats.steps.size(), kTimes.size());
  EXPECT_FALSE(run.underWay());
  EXPECT_EQ(run.stepToRead(), kTimes.size() - 1);  // finished: the last step, not read again
  EXPECT_EQ(run.path(), dir + "piped.afam");

  RunEncoder direct(dir + "direct.afam", options(), PipelineRun::kKeyInterval);
  for (size_t k = 0; k < kTimes.size(); ++k) direct.addStep(*series.steps[k], kTimes[k]);
  direct.commit();
  const std::string piped = fileBytes(dir + "piped.afam");
  EXPECT_GT(piped.size(), 0u);
  EXPECT_EQ(piped, fileBytes(dir + "direct.afam"));
  EXPECT_EQ(AfamFile::open(dir + "piped.afam")->stepTimes(), kTimes);
  EXPECT_GT(stats.references[1] + stats.residuals[1], 0);  // step 1 coded in time on step 0
}

TEST(PipelineRun, StartsOnlyAtTheFirstStep) {
  PipelineRun run;
  run.setTimes(kTimes);
  EXPECT_FALSE(run.readyToStart(kTimes[1]));  // the pipeline delivered another step first
  EXPECT_FALSE(run.underWay());
  EXPECT_EQ(run.stepToRead(), 0u);
  EXPECT_TRUE(run.readyToStart(kTimes[0]));
  EXPECT_TRUE(run.readyToStart(kUnknownTime));
  PipelineRun timeless;
  EXPECT_FALSE(timeless.readyToStart(kUnknownTime));
  EXPECT_THROW(timeless.start(scratchDir("timeless/") + "x.afam", options()), InvalidArgument);
}

TEST(PipelineRun, AStepOfAnotherGridLeavesNoFileAndStartsAgain) {
  const std::string dir = scratchDir("grid/");
  afam_test::InMemoryRun series(kDims, waves(kTimes.size()));
  const std::vector<float> smaller(size_t(kDims[0] * kDims[1] * (kDims[2] - 2)), 0.5f);
  ArraySource other(smaller.data(), {kDims[0], kDims[1], kDims[2] - 2});
  PipelineRun run;
  startRun(run, dir + "run.afam");
  run.addStep(*series.steps[0]);
  try {
    run.addStep(other);
    ADD_FAILURE() << "a step of another grid joined the run";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("step 1"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(run.underWay());
  EXPECT_EQ(run.stepToRead(), 0u);  // the next run starts at the first step again
  EXPECT_EQ(filesIn(dir), 0u);      // neither the run nor a temporary file
  EXPECT_THROW(run.addStep(*series.steps[2]), InvalidArgument);
}

TEST(PipelineRun, ProgressRunsAcrossTheStepsAndACancelLeavesNoFile) {
  const std::string dir = scratchDir("progress/");
  afam_test::InMemoryRun series(kDims, waves(kTimes.size()));
  PipelineRun run;
  startRun(run, dir + "run.afam");
  std::vector<std::pair<size_t, double>> seen;  // (step under way, fraction of the run)
  run.setProgress([&](double f) {
    seen.emplace_back(run.stepToRead(), f);
    return true;
  });
  for (size_t k = 0; k < kTimes.size(); ++k) run.addStep(*series.steps[k]);
  ASSERT_FALSE(seen.empty());
  const double n = double(kTimes.size());
  for (size_t i = 0; i < seen.size(); ++i) {
    EXPECT_GE(seen[i].second, double(seen[i].first) / n - 1e-12) << i;
    EXPECT_LE(seen[i].second, double(seen[i].first + 1) / n + 1e-12) << i;
    if (i > 0) {
      EXPECT_GE(seen[i].second, seen[i - 1].second) << i;
    }
  }
  EXPECT_EQ(seen.front().first, 0u);
  EXPECT_EQ(seen.back().first, kTimes.size() - 1);
  EXPECT_GT(seen.back().second, (n - 1) / n);

  PipelineRun cancelled;
  startRun(cancelled, dir + "cancelled.afam");
  cancelled.setProgress([&](double f) { return f < 1.0 / n + 0.1; });  // cancels step 1
  cancelled.addStep(*series.steps[0]);
  EXPECT_THROW(cancelled.addStep(*series.steps[1]), Cancelled);
  EXPECT_FALSE(cancelled.underWay());
  EXPECT_EQ(cancelled.stepToRead(), 0u);
  run.drop();  // the first run, under way, goes too
  EXPECT_EQ(filesIn(dir), 0u);
}

TEST(PipelineRun, AFinishedRunStaysCurrentUntilItsTimesChange) {
  const std::string dir = scratchDir("current/");
  afam_test::InMemoryRun series(kDims, waves(kTimes.size()));
  PipelineRun run;
  EXPECT_EQ(run.finishedFrom(), nullptr);
  startRun(run, dir + "run.afam");
  for (size_t k = 0; k < kTimes.size(); ++k) {
    EXPECT_THROW(run.commit(RunOrigin{}), InvalidArgument);  // not every step yet
    EXPECT_TRUE(run.underWay());
    run.addStep(*series.steps[k]);
  }
  EXPECT_THROW(run.addStep(*series.steps[0]), InvalidArgument);  // a fourth step of three
  run.commit(RunOrigin{7, 42});
  ASSERT_NE(run.finishedFrom(), nullptr);
  EXPECT_EQ(run.finishedFrom()->settings, 7u);
  EXPECT_EQ(run.finishedFrom()->input, 42u);
  run.setTimes(kTimes);  // the same times: still current
  ASSERT_NE(run.finishedFrom(), nullptr);
  EXPECT_EQ(run.stepToRead(), kTimes.size() - 1);
  run.setTimes({0.5, 1.0, 2.5, 3.0});  // another run
  EXPECT_EQ(run.finishedFrom(), nullptr);
  EXPECT_EQ(run.stepToRead(), 0u);
  EXPECT_TRUE(std::filesystem::exists(dir + "run.afam"));  // a finished run's file is the caller's
  EXPECT_THROW(run.commit(RunOrigin{}), InvalidArgument);  // nothing under way
}

TEST(PipelineRun, AFillValueIsDeclaredFromTheFirstStepAndWarnedOnlyWhenNeverFound) {
  const std::string dir = scratchDir("fill/");
  afam_test::InMemoryRun series(kDims, waves(kTimes.size()));
  EncoderOptions opt = options();
  opt.hasMissingValue = true;
  opt.missingValue = -5.0;
  for (const bool foundAtStep1 : {false, true}) {
    const std::string path = dir + (foundAtStep1 ? "found.afam" : "never.afam");
    PipelineRun run;
    startRun(run, path, opt);
    for (size_t k = 0; k < kTimes.size(); ++k) {
      run.addStep(*series.steps[k]);
      run.noteFillValue(foundAtStep1 && k == 1);
    }
    EXPECT_EQ(run.fillValueNeverFound(), !foundAtStep1);
    run.commit(RunOrigin{});
    const auto file = AfamFile::open(path, 0);
    EXPECT_EQ(file->header().missing, MissingKind::Value);
    EXPECT_EQ(file->header().missingValue, -5.0);
  }
  PipelineRun plain;  // without a fill value there is nothing to warn about
  startRun(plain, dir + "plain.afam");
  EXPECT_FALSE(plain.fillValueNeverFound());
}
