// SPDX-License-Identifier: BSD-3-Clause
// The encoder's batched least-squares residuals on the GPU (least_squares_batch.hpp): the one
// place a front end asks for them (afam encode --device, the ParaView encoding filter). Built in
// every build: without nvcc, or where no GPU is usable, it says why and returns null (the encoder
// then fits every question on the CPU). Plain C++ header.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "afam/search/least_squares_batch.hpp"

namespace afam {

/// GPU residuals on CUDA device `device` (-1: the MPI local rank's, as the ray caster picks it,
/// device_selection.hpp), or null with the reason given to `report`. The doubles
/// equal CpuLeastSquaresBatch's bit for bit (least_squares_order.hpp); requests whose block does
/// not fit a thread block's shared memory are computed by the CPU reference.
std::shared_ptr<LeastSquaresBatch> makeGpuLeastSquares(
    const std::function<void(const std::string&)>& report, int device = -1);

}  // namespace afam
