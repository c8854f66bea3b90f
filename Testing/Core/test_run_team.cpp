// SPDX-License-Identifier: BSD-3-Clause
// A run encoded by a team of processes (threads standing in for MPI ranks, as pvbatch's ranks
// encode a time series): the file one process writes, byte for byte, coded in time (references
// and residuals); the other members' scratch runs leave nothing behind; a step refused on one
// member is refused on all.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/encode/encode_run.hpp"
#include "moving_blob.hpp"
#include "scratch_dir.hpp"
#include "thread_team.hpp"

using namespace afam;

namespace {

const Index3 kDims{36, 32, 28};

std::string scratchDir() {  // inside the process's scratch folder, removed at exit
  const std::string dir = afam_test::scratchPath("afam_run_team/");
  std::filesystem::create_directories(dir);
  return dir;
}

std::string fileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

/// Steps that drift everywhere (residuals) with a blob that moves (references elsewhere).
std::vector<std::vector<float>> steps(int count) {
  std::vector<std::vector<float>> out;
  for (int k = 0; k < count; ++k) {
    std::vector<float> v = afam_test::driftingWaves(kDims, k);
    const std::vector<float> blob = afam_test::movingBlob(kDims, k);
    for (size_t i = 0; i < v.size(); ++i) v[i] += blob[i];
    out.push_back(std::move(v));
  }
  return out;
}

struct MemberRun {
  RunStats stats;
  std::string error;
};

/// Every member encodes the run with its own RunEncoder at `path` (the first writes it), each
/// step's source handed to every member; member `badMember` gets a step of another grid at
/// step 1 when it is >= 0.
std::vector<MemberRun> encodeAsTeam(afam_test::InMemoryRun& series, int members,
                                    const std::string& path, int badMember = -1) {
  afam_test::ThreadTeamHub hub(members);
  std::vector<MemberRun> result(static_cast<size_t>(members));
  std::vector<std::thread> threads;
  EncoderOptions opt = afam_test::runTestOptions(3);
  opt.threads = 1;
  const std::vector<float> other(size_t(kDims[0] * kDims[1] * (kDims[2] - 1)), 1.0f);
  for (int r = 0; r < members; ++r)
    threads.emplace_back([&, r] {
      afam_test::ThreadTeam team(hub, r);
      try {
        RunEncoder encoder(path, opt, 3);
        for (size_t k = 0; k < series.steps.size(); ++k) {
          ArraySource smaller(other.data(), {kDims[0], kDims[1], kDims[2] - 1});
          VolumeSource& step = (r == badMember && k == 1) ? smaller : *series.steps[k];
          encoder.addStep(step, 0.5 * double(k), team);
        }
        result[size_t(r)].stats = encoder.commit(team);
      } catch (const std::exception& e) {
        result[size_t(r)].error = e.what();
      }
    });
  for (std::thread& t : threads) t.join();
  return result;
}

}  // namespace

TEST(RunTeam, ARunEncodedByATeamIsTheFileOneProcessWrites) {
  afam_test::InMemoryRun series(kDims, steps(6));
  const std::string dir = scratchDir(), alone = dir + "alone.afam", team = dir + "team.afam";
  EncoderOptions opt = afam_test::runTestOptions(3);
  opt.threads = 1;
  RunStats one;
  {
    RunEncoder encoder(alone, opt, 3);
    for (size_t k = 0; k < series.steps.size(); ++k)
      encoder.addStep(*series.steps[k], 0.5 * double(k));
    one = encoder.commit();
  }
  int64_t references = 0, residuals = 0;
  for (size_t k = 0; k < one.steps.size(); ++k) {
    references += one.references[k];
    residuals += one.residuals[k];
  }
  ASSERT_GT(references, 0) << "the run must refer to earlier steps for the test to mean anything";
  ASSERT_GT(residuals, 0) << "and code residuals on them";

  for (int members : {2, 3}) {
    SCOPED_TRACE(std::to_string(members) + " members");
    const std::vector<MemberRun> result = encodeAsTeam(series, members, team);
    for (const MemberRun& m : result) EXPECT_EQ(m.error, "");
    EXPECT_EQ(fileBytes(team), fileBytes(alone)) << "the same file, byte for byte";
    EXPECT_EQ(result[0].stats.bytesOut, one.bytesOut);
    EXPECT_EQ(result[0].stats.references, one.references);
    EXPECT_EQ(result[0].stats.residuals, one.residuals);
    EXPECT_DOUBLE_EQ(result[1].stats.bound, one.bound) << "every member holds the run's bound";
    std::remove(team.c_str());
  }
  // Only the run written alone is left: no member's scratch run, no temporary file.
  std::vector<std::string> left;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    left.push_back(e.path().filename().string());
  EXPECT_EQ(left, std::vector<std::string>{"alone.afam"});
  std::filesystem::remove_all(dir);
}

TEST(RunTeam, AStepRefusedOnOneMemberIsRefusedOnAllAndNothingIsWritten) {
  afam_test::InMemoryRun series(kDims, steps(3));
  const std::string dir = scratchDir(), path = dir + "refused.afam";
  const std::vector<MemberRun> result = encodeAsTeam(series, 3, path, 2);
  for (size_t r = 0; r < result.size(); ++r) {
    SCOPED_TRACE("member " + std::to_string(r));
    EXPECT_NE(result[r].error.find("step 1"), std::string::npos) << result[r].error;
    EXPECT_NE(result[r].error.find("dims"), std::string::npos) << result[r].error;
  }
  EXPECT_NE(result[0].error.find("rank 2"), std::string::npos) << "named with its member";
  EXPECT_TRUE(std::filesystem::is_empty(dir)) << "no run, no scratch run, no temporary file";
  std::filesystem::remove_all(dir);
}
