// SPDX-License-Identifier: BSD-3-Clause
// The encoder's coarse levels filtered on the GPU from a copy of the volume in device memory
// (level_sampler.hpp): the one place a front end asks for it (afam encode --device, the ParaView
// encoding filter), beside makeGpuLeastSquares. Built in every build: without nvcc, or where no
// GPU is usable, it says why and returns null (the encoder then filters on the CPU). Plain C++.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <string>

#include "afam/sampling/level_sampler.hpp"

namespace afam {

/// Device memory a level sampler leaves free for the encode's other GPU work (its least-squares
/// batches) when it has no budget of its own.
constexpr size_t kGpuEncodeReserveBytes = size_t(2) << 30;

/// A level sampler on CUDA device `device` (-1: the MPI local rank's, device_selection.hpp), or
/// null with the reason given to `report`. It holds a volume only where its copy takes at most
/// `volumeBudgetBytes` of device memory (0: what the device has free when it reserves, less
/// kGpuEncodeReserveBytes for the rest of the encode); otherwise reserve() says why. Its floats
/// equal CpuLevelSampler's bit for bit (level_filter.hpp).
std::shared_ptr<LevelSampler> makeGpuLevelSampler(
    const std::function<void(const std::string&)>& report, int device = -1,
    size_t volumeBudgetBytes = 0);

}  // namespace afam
