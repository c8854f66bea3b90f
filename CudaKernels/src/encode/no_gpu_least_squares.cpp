// SPDX-License-Identifier: BSD-3-Clause
// makeGpuLeastSquares of a build without nvcc: none, and the reason in words.
#include "afam/cuda/encode/make_gpu_least_squares.hpp"

namespace afam {

std::shared_ptr<LeastSquaresBatch> makeGpuLeastSquares(
    const std::function<void(const std::string&)>& report, int) {
  report("this build has no CUDA encoder (built without nvcc)");
  return nullptr;
}

}  // namespace afam
