// SPDX-License-Identifier: BSD-3-Clause
// `afam encode --device auto|gpu|cpu`: where the NCP searches' least-squares questions are answered
// ahead, a batch of blocks at a time (EncoderOptions::leastSquares, make_gpu_least_squares.hpp),
// and where the coarse levels are filtered (EncoderOptions::levelSampler, from a copy of the volume
// in the GPU's memory: make_gpu_level_sampler.hpp).
// auto (the default) takes the GPU when one is usable, silently the CPU otherwise; gpu says on
// stderr why it cannot and encodes on the CPU. The file is the same either way.
#pragma once

#include <cstdio>
#include <string>

#include "afam/base/errors.hpp"
#include "afam/cuda/encode/make_gpu_least_squares.hpp"
#include "afam/cuda/encode/make_gpu_level_sampler.hpp"
#include "afam/encode/encoder.hpp"

namespace afam::cli {

inline const char* encodeDeviceHelp() {
  return "  --device D        where the NCP searches are asked ahead: auto (default: the GPU\n"
         "                    when one is usable), gpu (says why not, then the CPU) or cpu; the\n"
         "                    same file either way\n";
}

/// Sets opt.leastSquares for `device`; returns what answers ("cpu", or "gpu <name>").
inline std::string useEncodeDevice(EncoderOptions& opt, const std::string& device) {
  if (device != "auto" && device != "gpu" && device != "cpu")
    throw InvalidArgument("--device must be auto, gpu or cpu, not '" + device + "'");
  if (device == "cpu") return "cpu";
  const auto report = [&](const std::string& why) {
    if (device == "gpu")
      std::fprintf(stderr, "afam encode: --device gpu: %s; encoding on the CPU\n", why.c_str());
  };
  opt.leastSquares = makeGpuLeastSquares(report);
  if (!opt.leastSquares) return "cpu";
  opt.levelSampler = makeGpuLevelSampler(report);
  return "gpu " + opt.leastSquares->description();
}

}  // namespace afam::cli
