// SPDX-License-Identifier: BSD-3-Clause
// The cases of the bound-promise sweep (test_bound_promise.cpp, and its GPU twin
// Testing/Cuda/test_gpu_bound_promise.cpp): deterministic random volumes of every small shape,
// value scales from 1e-30 to 1e30, constant, noise and smooth content, both bound kinds, with and
// without missing samples, one volume or a run of two steps; each encoded to a file or refused.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "afam/encode/encode_run.hpp"
#include "afam/encode/encoder.hpp"

namespace afam_test {

enum class Content { Constant, Noise, Smooth };
inline const char* contentName(Content c) {
  return c == Content::Constant ? "constant" : c == Content::Noise ? "noise" : "smooth";
}

struct PromiseCase {
  afam::Index3 dims;
  double scale;
  Content content;
  afam::BoundKind kind;
  double bound;  ///< relative to the value range
  bool missing;
  bool run;
  std::string name() const {
    char buf[200];
    std::snprintf(buf, sizeof buf, "%lldx%lldx%lld %s scale %g %s %g%s%s", (long long)dims[0],
                  (long long)dims[1], (long long)dims[2], contentName(content), scale,
                  afam::boundKindName(kind), bound, missing ? " missing" : "", run ? " run" : "");
    return buf;
  }
};

/// The case's volume (step 0 or 1 of a run: step 1 moves every sample a little).
inline std::vector<float> volumeOf(const PromiseCase& c, int step, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0, 1);
  std::uniform_real_distribution<double> uniform(0, 1);
  const afam::Index3 d = c.dims;
  std::vector<float> v(size_t(d[0] * d[1] * d[2]));
  size_t i = 0;
  for (int64_t z = 0; z < d[2]; ++z)
    for (int64_t y = 0; y < d[1]; ++y)
      for (int64_t x = 0; x < d[0]; ++x, ++i) {
        double value = 0.7;
        if (c.content == Content::Noise) value = normal(rng);
        if (c.content == Content::Smooth)
          value = std::sin(0.4 * double(x) + 0.1 * step) * std::cos(0.3 * double(y)) +
                  0.5 * std::sin(0.2 * double(z));
        if (step == 1 && c.content != Content::Constant) value += 0.05 * normal(rng);
        v[i] = float(c.scale * value);
        if (c.missing && i > 0 && uniform(rng) < 0.25) v[i] = NAN;  // sample 0 stays valid
      }
  return v;
}

inline afam::EncoderOptions optionsOf(const PromiseCase& c) {
  afam::EncoderOptions opt;
  opt.errorBound = c.bound;
  opt.relativeBound = true;
  opt.boundKind = c.kind;
  opt.threads = 1;
  return opt;
}

/// A case encoded to `path` (with `opt`), or refused: its steps' volumes and sources.
struct EncodedCase {
  std::vector<std::vector<float>> volumes;
  std::vector<std::unique_ptr<afam::ArraySource>> sources;
  bool refused = false;
  std::string error;  ///< why, when refused
};

/// Encodes the case (one volume, or a run of two steps) to `path`. A refusal must leave no file.
inline EncodedCase encodeCase(const PromiseCase& c, uint32_t seed, const afam::EncoderOptions& opt,
                              const std::string& path) {
  EncodedCase out;
  out.volumes.push_back(volumeOf(c, 0, seed));
  if (c.run) out.volumes.push_back(volumeOf(c, 1, seed + 1));
  std::vector<afam::VolumeSource*> steps;
  for (std::vector<float>& v : out.volumes) {
    out.sources.push_back(std::make_unique<afam::ArraySource>(v.data(), c.dims, "v"));
    steps.push_back(out.sources.back().get());
  }
  try {
    if (c.run)
      afam::encodeRun(steps, opt, afam::RunOptions{}, path);
    else
      afam::encodeVolume(*steps[0], opt, path);
  } catch (const afam::Error& e) {
    EXPECT_FALSE(std::filesystem::exists(path))
        << "a refused encode left " << path << ": " << e.what();
    out.refused = true;
    out.error = e.what();
  }
  return out;
}

inline std::vector<afam::Index3> smallShapes() {
  std::vector<afam::Index3> shapes;
  for (int z = 1; z <= 5; ++z)
    for (int y = 1; y <= 5; ++y)
      for (int x = 1; x <= 5; ++x) shapes.push_back({x, y, z});
  for (int thin = 1; thin <= 2; ++thin)
    for (int a = 0; a < 3; ++a) {
      afam::Index3 d{64, 64, 64};
      d[size_t(a)] = thin;
      shapes.push_back(d);
    }
  return shapes;
}

inline const double kScales[] = {1e-30, 1e-10, 1.0, 1e10, 1e30};
inline const double kBounds[] = {1e-1, 1e-2, 1e-3, 1e-4, 1e-5};
inline const Content kContents[] = {Content::Constant, Content::Noise, Content::Smooth};
inline const afam::BoundKind kKinds[] = {afam::BoundKind::Rmse, afam::BoundKind::MaxError};

/// 2x2x2 noise at every bound and kind, 40 seeds.
template <typename Visit>
void forEachTwoByTwoCase(Visit&& visit) {
  for (uint32_t seed = 0; seed < 40; ++seed)
    for (const double bound : kBounds)
      for (const afam::BoundKind kind : kKinds)
        visit(PromiseCase{{2, 2, 2}, 1.0, Content::Noise, kind, bound, false, false}, seed);
}

/// Each small shape once, the settings turning through their values so that every value of each
/// setting meets many shapes; a run and missing samples on every third and fifth shape.
template <typename Visit>
void forEachRotatingShapeCase(Visit&& visit) {
  const std::vector<afam::Index3> shapes = smallShapes();
  for (size_t i = 0; i < shapes.size(); ++i)
    visit(PromiseCase{shapes[i], kScales[i % 5], kContents[(i / 5 + i) % 3], kKinds[(i / 3) % 2],
                      kBounds[(i * 3) % 5], i % 3 == 1, i % 5 == 2},
          uint32_t(100 + i));
}

/// Pointwise bounds in runs at the extreme scales, where the sweep found blocks a float32
/// rounding over a pointwise bound as the reader evaluates them.
template <typename Visit>
void forEachPointwiseRunCase(Visit&& visit) {
  uint32_t seed = 500;
  for (const afam::Index3 d :
       {afam::Index3{1, 3, 2}, afam::Index3{4, 3, 2}, afam::Index3{4, 4, 4}, afam::Index3{5, 4, 3}})
    for (const double scale : {1e-30, 1.0, 1e30})
      for (const Content content : {Content::Noise, Content::Smooth})
        for (const double bound : {1e-3, 1e-5})
          visit(PromiseCase{d, scale, content, afam::BoundKind::MaxError, bound, false, true},
                seed++);
}

/// The default suite's selection of the sweep, case by case with its seed.
template <typename Visit>
void forEachDefaultCase(Visit&& visit) {
  forEachTwoByTwoCase(visit);
  forEachRotatingShapeCase(visit);
  forEachPointwiseRunCase(visit);
}

/// The 2x2x2 standard-normal volume whose interpolant with rounded points at 1e-3 coded into
/// exactly the 32 bytes of its float32 samples: a reader took the coded bytes for floats.
inline std::vector<float> theVolumeThatDecodedTo1e24() {
  return {0.34558418f, 0.82161814f, 0.33043706f, -1.3031572f,
          0.9053559f,  0.44637457f, -0.5369532f, 0.5811181f};
}

}  // namespace afam_test
