// SPDX-License-Identifier: BSD-3-Clause
// One GPU per MPI rank: the device a process picks from its launcher's environment.
#include <gtest/gtest.h>

#include <map>
#include <optional>
#include <string>
#include <vector>

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

namespace {

std::vector<DeviceUuid> uuids(int count) {
  std::vector<DeviceUuid> out(static_cast<size_t>(count));
  for (int d = 0; d < count; ++d) out[size_t(d)].fill(uint8_t(0x10 + d));
  return out;
}

}  // namespace

TEST(DeviceSelection, AloneOnItsNodeTheOpenGlContextsGpu) {
  const auto gpus = uuids(4);
  const GpuChoice c = chooseGpuDevice(gpus, gpus[2], fakeEnv({}));
  EXPECT_EQ(c.device, 2) << "no launcher: interop's GPU, not device 0";
  EXPECT_EQ(c.why, "the OpenGL context's GPU");
  EXPECT_EQ(chooseGpuDevice(
                gpus, gpus[3],
                fakeEnv({{"OMPI_COMM_WORLD_LOCAL_RANK", "0"}, {"OMPI_COMM_WORLD_LOCAL_SIZE", "1"}}))
                .device,
            3)
      << "one rank on its node";
  EXPECT_EQ(chooseGpuDevice(gpus, gpus[1], fakeEnv({{"AFAM_CUDA_DEVICE", "0"}})).device, 0)
      << "an explicit choice wins";
}

TEST(DeviceSelection, RanksWithTheirOwnOpenGlGpusUseThem) {
  const auto gpus = uuids(4);
  for (int rank = 0; rank < 4; ++rank) {
    const auto env = fakeEnv({{"OMPI_COMM_WORLD_LOCAL_RANK", std::to_string(rank)},
                              {"OMPI_COMM_WORLD_LOCAL_SIZE", "4"}});
    const GpuChoice c = chooseGpuDevice(gpus, gpus[size_t(rank)], env);
    EXPECT_EQ(c.device, rank);
    EXPECT_EQ(c.why, "the OpenGL context's GPU");
  }
}

TEST(DeviceSelection, RanksSharingOneOpenGlGpuStillSpreadOverTheGpus) {
  const auto gpus = uuids(2);
  for (int rank = 0; rank < 2; ++rank) {
    const auto env = fakeEnv({{"MPI_LOCALRANKID", std::to_string(rank)}, {"MPI_LOCALNRANKS", "2"}});
    const GpuChoice c = chooseGpuDevice(gpus, gpus[0], env);
    EXPECT_EQ(c.device, rank) << "rank " << rank << ": N ranks on N GPUs, interop or not";
    EXPECT_EQ(c.why.find("runs on GPU 0") != std::string::npos, rank == 1) << c.why;
  }
}

TEST(DeviceSelection, AnOpenGlOnNoCudaDeviceIsIgnored) {
  const auto gpus = uuids(2);
  DeviceUuid mesa{};
  mesa.fill(0xee);  // llvmpipe reports a UUID of its own
  EXPECT_EQ(chooseGpuDevice(gpus, mesa, fakeEnv({{"SLURM_LOCALID", "1"}})).device, 1);
  EXPECT_EQ(chooseGpuDevice(gpus, std::nullopt, fakeEnv({})).device, 0);
  EXPECT_EQ(chooseGpuDevice({}, mesa, fakeEnv({})).device, -1);
  EXPECT_EQ(localSizeFromEnvironment(fakeEnv({{"OMPI_COMM_WORLD_LOCAL_SIZE", "0"}})), -1);
  EXPECT_EQ(localSizeFromEnvironment(fakeEnv({{"MV2_COMM_WORLD_LOCAL_SIZE", "3"}})), 3);
}
