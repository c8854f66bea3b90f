// SPDX-License-Identifier: BSD-3-Clause
// A slowly evolving run for the time-series tests: a smooth background that never changes, a blob
// that moves along x by `shift` voxels a step (only the blocks it crosses change) and fixed noise;
// and what the tests hand encodeRun.
#pragma once

#include <cmath>
#include <random>
#include <vector>

#include "afam/encode/encoder.hpp"
#include "afam/volume/volume_source.hpp"

namespace afam_test {

inline std::vector<float> movingBlob(afam::Index3 dims, int step, double shift = 3.0) {
  std::vector<float> v(size_t(dims[0] * dims[1] * dims[2]));
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0, 0.2f);
  size_t i = 0;
  for (int64_t z = 0; z < dims[2]; ++z)
    for (int64_t y = 0; y < dims[1]; ++y)
      for (int64_t x = 0; x < dims[0]; ++x, ++i) {
        const double cx = 8 + shift * step,
                     r2 = (x - cx) * (x - cx) + (y - 10) * (y - 10) + (z - 8) * (z - 8);
        v[i] = float(20 + 5 * std::sin(0.1 * x + 0.07 * y) + 40 * std::exp(-r2 / 20)) + noise(rng);
      }
  return v;
}

/// Step k of a field that drifts everywhere, slowly: waves whose phase moves by `drift` a step
/// (about a tenth of the bound's worth of change), plus fixed noise (so the models spend their
/// budget and a reference to the step before rarely stays within it).
inline std::vector<float> driftingWaves(afam::Index3 dims, int k, double drift = 0.02) {
  std::vector<float> v(size_t(dims[0] * dims[1] * dims[2]));
  std::mt19937 rng(11);
  std::normal_distribution<float> noise(0, 0.3f);
  size_t i = 0;
  for (int64_t z = 0; z < dims[2]; ++z)
    for (int64_t y = 0; y < dims[1]; ++y)
      for (int64_t x = 0; x < dims[0]; ++x, ++i)
        v[i] = float(50 + 20 * std::sin(0.21 * x + drift * k) * std::cos(0.17 * y - 0.13 * z) +
                     10 * std::sin(0.3 * z + 0.5 * drift * k)) +
               noise(rng);
  return v;
}

/// Steps held in memory with the sources and pointers encodeRun takes (not copyable: the sources
/// point into data).
struct InMemoryRun {
  std::vector<std::vector<float>> data;
  std::vector<afam::ArraySource> sources;
  std::vector<afam::VolumeSource*> steps;
  InMemoryRun(afam::Index3 dims, std::vector<std::vector<float>> values) : data(std::move(values)) {
    sources.reserve(data.size());
    for (const auto& d : data) sources.emplace_back(d.data(), dims);
    for (auto& s : sources) steps.push_back(&s);
  }
  InMemoryRun(const InMemoryRun&) = delete;
  InMemoryRun& operator=(const InMemoryRun&) = delete;
};

/// The run tests' coding: a relative RMSE bound of 1e-2, 2 levels, `blocks` finest blocks a side.
inline afam::EncoderOptions runTestOptions(int blocks) {
  afam::EncoderOptions opt;
  opt.errorBound = 1e-2;
  opt.relativeBound = true;
  opt.levels = 2;
  opt.blocksPerAxis = blocks;
  return opt;
}

}  // namespace afam_test
