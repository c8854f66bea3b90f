// SPDX-License-Identifier: BSD-3-Clause
// Helpers of the renderer tests: small Marschner-Lobb encodings written to temporary files.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "afam/encode/encoder.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/render/renderer.hpp"
#include "afam/scene/transfer_function.hpp"
#include "afam/volume/marschner_lobb.hpp"
#include "scratch_dir.hpp"

namespace afam_test {

inline std::string tempPath(const std::string& stem) { return scratchPath(stem + ".afam"); }

/// ML (default parameters, [-1, 1]^3) sampled on n^3, encoded with the given mode; cached per
/// process so several tests share one encoding.
inline std::shared_ptr<const afam::AfamFile> encodeMl(int n, afam::EncodingMode mode,
                                                      int levels = 3, int blocks = 4,
                                                      double bound = 1e-3, int fixedNcp = 0,
                                                      int degree = 2) {
  const std::string path = tempPath(std::to_string(n) + "_" + afam::modeName(mode) + "_" +
                                    std::to_string(levels) + "_" + std::to_string(blocks) + "_" +
                                    std::to_string(fixedNcp) + "_p" + std::to_string(degree));
  if (::access(path.c_str(), R_OK) != 0) {
    std::vector<float> data(size_t(n) * n * n);
    afam::MarschnerLobb ml;
    afam::marschnerLobbSlab(ml, {n, n, n}, 0, n, data.data());
    afam::ArraySource src(data.data(), {n, n, n});
    afam::EncoderOptions o;
    o.levels = levels;
    o.blocksPerAxis = blocks;
    o.degree = degree;
    o.errorBound = bound;
    o.mode = mode;
    o.fixedNcp = fixedNcp;
    o.threads = 2;
    afam::encodeVolume(src, o, path);
  }
  return afam::AfamFile::open(path);
}

/// A smooth field with a scan's noise (`sigma`, 0.5% of its range by default) in a 96^3 volume,
/// two levels of 4^3 finest blocks, bound 1e-2, with the given entropy stage: coded splines (in
/// lanes frames under Lanes), the payloads a GPU decodes; with noise above the bound (3%), coded
/// samples (interpolants). Encoded once per process, stage and sigma.
inline std::shared_ptr<const afam::AfamFile> encodeNoisyField(afam::EntropyStage stage,
                                                              double sigma = 0.005) {
  const std::string path = tempPath(std::string("noisy_field_") + afam::entropyStageName(stage) +
                                    "_" + std::to_string(sigma));
  if (::access(path.c_str(), R_OK) != 0) {
    const int n = 96;
    std::vector<float> v(size_t(n) * n * n);
    std::mt19937 rng(2);
    std::normal_distribution<double> noise(0, sigma);
    size_t i = 0;
    for (int z = 0; z < n; ++z)
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
          v[i++] = float(0.5 + 0.5 * std::sin(x / 7.0) * std::cos(y / 9.0) * std::sin(z / 11.0) +
                         noise(rng));
    afam::ArraySource src(v.data(), {n, n, n});
    afam::EncoderOptions o;
    o.levels = 2;
    o.blocksPerAxis = 4;
    o.errorBound = 1e-2;
    o.entropy = stage;
    o.threads = 2;
    afam::encodeVolume(src, o, path);
  }
  return afam::AfamFile::open(path);
}

/// A ramp from transparent below `from` to opaque at the top of [lo, hi], coloured from `red`.
inline afam::TransferFunction ramp(double lo, double hi, double from, double red) {
  afam::TransferFunction tf;
  tf.colors = {{lo, red, 0.2, 0.3}, {hi, 1.0, 0.9, red}};
  tf.opacities = {{lo, 0.0}, {from, 0.0}, {hi, 0.8}};
  tf.referenceDistance = 0.02;
  return tf;
}

/// The largest channel difference of two images of the same size.
inline float maxDifference(const afam::ImageRGBA& a, const afam::ImageRGBA& b) {
  float most = 0;
  for (size_t i = 0; i < a.rgba.size(); ++i)
    most = std::max(most, std::fabs(a.rgba[i] - b.rgba[i]));
  return most;
}

/// The largest opacity of an image (0: transparent everywhere).
inline float largestAlpha(const afam::ImageRGBA& im) {
  float most = 0;
  for (size_t i = 3; i < im.rgba.size(); i += 4) most = std::max(most, im.rgba[i]);
  return most;
}

/// What two renderers of one file hold after drawing the same frame, one whose cache keeps models
/// in their compact form and one whose cache keeps floats.
struct CompactAndFloats {
  uint64_t compactBytes = 0, floatBytes = 0;
  size_t compactBlocks = 0, floatBlocks = 0;
};

/// Draws one frame of `file` (every block at the finest level, ramp(0, 255, from, 0.3), size^2
/// pixels) with a compact cache and with a float cache, records a failure unless the two images
/// are equal bit for bit, and tells what each cache holds.
inline CompactAndFloats drawCompactAndFloats(const std::shared_ptr<const afam::AfamFile>& file,
                                             double from, int size) {
  afam::RenderOptions o;
  o.threads = 2;
  o.loadThreads = 2;
  o.lod.bandWidth = 100;  // every block finest
  o.transferFunction = ramp(0, 255, from, 0.3);
  const afam::Camera cam =
      afam::Camera::lookAt({1.2, 1.4, 1.0}, {0, 0, 0}, {0, 0, 1}, 50, size, size);
  afam::RenderOptions asFloats = o;
  asFloats.compactModels = false;
  afam::Renderer compact(file, o), floats(file, asFloats);
  afam::FrameStats a, b;
  const afam::ImageRGBA got = compact.renderFrame(cam, a);
  const afam::ImageRGBA want = floats.renderFrame(cam, b);
  EXPECT_EQ(got.rgba.size(), want.rgba.size());
  if (got.rgba.size() == want.rgba.size()) {
    EXPECT_EQ(0, std::memcmp(got.rgba.data(), want.rgba.data(), got.rgba.size() * sizeof(float)));
  }
  return {compact.cache().residentBytes(), floats.cache().residentBytes(),
          compact.cache().residentBlocks(), floats.cache().residentBlocks()};
}

}  // namespace afam_test
