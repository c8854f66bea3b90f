// SPDX-License-Identifier: BSD-3-Clause
// One GPU per MPI rank: the device a process picks from its launcher's environment.
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "afam/ranks/device_selection.hpp"

using namespace afam;

namespace {

EnvironmentLookup fakeEnv(const std::map<std::string, std::string>& vars) {
  return [vars](const char* name) -> const char* {
    const auto it = vars.find(name);
    return it == vars.end() ? nullptr : it->second.c_str();
  };
}

}  // namespace

TEST(DeviceSelection, EachLocalRankGetsItsOwnGpu) {
  for (int rank = 0; rank < 8; ++rank) {
    const auto env = fakeEnv({{"OMPI_COMM_WORLD_LOCAL_RANK", std::to_string(rank)}});
    EXPECT_EQ(localRankFromEnvironment(env), rank);
    EXPECT_EQ(selectGpuDevice(4, env), rank % 4) << "rank " << rank << " of 8 on 4 GPUs";
    EXPECT_EQ(selectGpuDevice(1, env), 0) << "one visible device (CUDA_VISIBLE_DEVICES per rank)";
  }
}

TEST(DeviceSelection, LaunchersAndOverrides) {
  EXPECT_EQ(localRankFromEnvironment(fakeEnv({{"MPI_LOCALRANKID", "3"}})), 3);
  EXPECT_EQ(localRankFromEnvironment(fakeEnv({{"MV2_COMM_WORLD_LOCAL_RANK", "2"}})), 2);
  EXPECT_EQ(localRankFromEnvironment(fakeEnv({{"SLURM_LOCALID", "5"}})), 5);
  EXPECT_EQ(localRankFromEnvironment(
                fakeEnv({{"OMPI_COMM_WORLD_LOCAL_RANK", "1"}, {"SLURM_LOCALID", "5"}})),
            1)
      << "Open MPI's variable first";
  EXPECT_EQ(localRankFromEnvironment(fakeEnv({})), -1);
  EXPECT_EQ(selectGpuDevice(2, fakeEnv({})), 0) << "no launcher: device 0";
  EXPECT_EQ(selectGpuDevice(4, fakeEnv({{"AFAM_CUDA_DEVICE", "2"}, {"SLURM_LOCALID", "1"}})), 2);
  EXPECT_EQ(selectGpuDevice(4, fakeEnv({{"AFAM_CUDA_DEVICE", "9"}, {"SLURM_LOCALID", "1"}})), 1)
      << "an out-of-range override falls back to the rank";
  EXPECT_EQ(selectGpuDevice(0, fakeEnv({})), -1);
}

TEST(DeviceSelection, GarbageIsNotARank) {
  for (const char* bad : {"", "-1", "x", "1x", "99999999999"})
    EXPECT_EQ(localRankFromEnvironment(fakeEnv({{"OMPI_COMM_WORLD_LOCAL_RANK", bad}})), -1) << bad;
}
