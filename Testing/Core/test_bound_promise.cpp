// SPDX-License-Identifier: BSD-3-Clause
// The bound is a promise: deterministic random volumes of every small shape (1 to 5 samples per
// axis, and slabs of 1-2 samples beside 64 along the other axes), value scales from 1e-30 to 1e30,
// constant, noise and smooth content, both bound kinds at 1e-1 to 1e-5, with and without missing
// samples, one volume or a run of two steps: every file decodes within its bound on every block of
// every level, as a reader decodes it (AfamFile::readPayload, the function `afam verify` and the
// renderer read through), and the compact form a cache keeps gives the same floats bit for bit.
// An encode may refuse instead (an error naming what is wrong), and then it leaves no file.
// BoundPromise.* runs a deterministic selection of the cases in the default suite;
// BoundPromiseSlow.* runs every combination (ctest label `slow`).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "afam/encode/encode_run.hpp"
#include "afam/encode/encoder.hpp"
#include "decoded_bound.hpp"
#include "scratch_dir.hpp"

using namespace afam;

namespace {

enum class Content { Constant, Noise, Smooth };
const char* contentName(Content c) {
  return c == Content::Constant ? "constant" : c == Content::Noise ? "noise" : "smooth";
}

struct PromiseCase {
  Index3 dims;
  double scale;
  Content content;
  BoundKind kind;
  double bound;  ///< relative to the value range
  bool missing;
  bool run;
  std::string name() const {
    char buf[200];
    std::snprintf(buf, sizeof buf, "%lldx%lldx%lld %s scale %g %s %g%s%s", (long long)dims[0],
                  (long long)dims[1], (long long)dims[2], contentName(content), scale,
                  boundKindName(kind), bound, missing ? " missing" : "", run ? " run" : "");
    return buf;
  }
};

/// The case's volume (step 0 or 1 of a run: step 1 moves every sample a little).
std::vector<float> volumeOf(const PromiseCase& c, int step, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0, 1);
  std::uniform_real_distribution<double> uniform(0, 1);
  const Index3 d = c.dims;
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

EncoderOptions optionsOf(const PromiseCase& c) {
  EncoderOptions opt;
  opt.errorBound = c.bound;
  opt.relativeBound = true;
  opt.boundKind = c.kind;
  opt.threads = 1;
  return opt;
}

bool checkCase(const PromiseCase& c, uint32_t seed) {
  SCOPED_TRACE(c.name());
  const std::string path = afam_test::scratchPath("promise.afam");
  std::vector<float> v0 = volumeOf(c, 0, seed), v1;
  ArraySource s0(v0.data(), c.dims, "v");
  std::vector<VolumeSource*> steps{&s0};
  std::unique_ptr<ArraySource> s1;
  if (c.run) {
    v1 = volumeOf(c, 1, seed + 1);
    s1 = std::make_unique<ArraySource>(v1.data(), c.dims, "v");
    steps.push_back(s1.get());
  }
  try {
    if (c.run)
      encodeRun(steps, optionsOf(c), RunOptions{}, path);
    else
      encodeVolume(s0, optionsOf(c), path);
  } catch (const Error& e) {
    EXPECT_FALSE(std::filesystem::exists(path))
        << "a refused encode left " << path << ": " << e.what();
    std::printf("refused: %s: %s\n", c.name().c_str(), e.what());
    return false;  // refused, by name
  }
  for (size_t step = 0; step < steps.size(); ++step) {
    SCOPED_TRACE("step " + std::to_string(step));
    auto f = AfamFile::open(path, int64_t(step));
    afam_test::expectEveryBlockWithinItsBound(*f, *steps[step]);
  }
  std::filesystem::remove(path);
  return true;
}

std::vector<Index3> smallShapes() {
  std::vector<Index3> shapes;
  for (int z = 1; z <= 5; ++z)
    for (int y = 1; y <= 5; ++y)
      for (int x = 1; x <= 5; ++x) shapes.push_back({x, y, z});
  for (int thin = 1; thin <= 2; ++thin)
    for (int a = 0; a < 3; ++a) {
      Index3 d{64, 64, 64};
      d[size_t(a)] = thin;
      shapes.push_back(d);
    }
  return shapes;
}

const double kScales[] = {1e-30, 1e-10, 1.0, 1e10, 1e30};
const double kBounds[] = {1e-1, 1e-2, 1e-3, 1e-4, 1e-5};
const Content kContents[] = {Content::Constant, Content::Noise, Content::Smooth};
const BoundKind kKinds[] = {BoundKind::Rmse, BoundKind::MaxError};

}  // namespace

TEST(BoundPromise, TheTwoByTwoByTwoVolumeThatDecodedTo1e24) {
  // Standard normal values whose interpolant with rounded points at 1e-3 codes into exactly the
  // 32 bytes of its float32 samples: a reader took the coded bytes for floats.
  std::vector<float> v{0.34558418f, 0.82161814f, 0.33043706f, -1.3031572f,
                       0.9053559f,  0.44637457f, -0.5369532f, 0.5811181f};
  ArraySource src(v.data(), {2, 2, 2}, "v");
  const std::string path = afam_test::scratchPath("two.afam");
  for (const double bound : kBounds) {
    SCOPED_TRACE(bound);
    EncoderOptions opt;
    opt.errorBound = bound;
    opt.relativeBound = true;
    encodeVolume(src, opt, path);
    auto f = AfamFile::open(path);
    if (bound == 1e-3) {
      const ModelEntry& e = f->entries()[0];
      EXPECT_TRUE(e.kind == BlockKind::Interpolant && e.roundedPoints && e.storedSize == e.size)
          << "no longer the case that decoded to 1e24: " << blockKindName(e.kind) << " of "
          << e.storedSize << " bytes";
    }
    afam_test::expectEveryBlockWithinItsBound(*f, src);
  }
  std::filesystem::remove(path);
}

TEST(BoundPromise, TwoByTwoByTwoNoiseAtEveryBound) {
  for (uint32_t seed = 0; seed < 40; ++seed)
    for (const double bound : kBounds)
      for (const BoundKind kind : kKinds)
        checkCase(PromiseCase{{2, 2, 2}, 1.0, Content::Noise, kind, bound, false, false}, seed);
}

TEST(BoundPromise, EverySmallShapeWithRotatingSettings) {
  // Each shape once, the settings turning through their values so that every value of each
  // setting meets many shapes; a run and missing samples on every third and fifth shape.
  const std::vector<Index3> shapes = smallShapes();
  for (size_t i = 0; i < shapes.size(); ++i) {
    const PromiseCase c{shapes[i],           kScales[i % 5],       kContents[(i / 5 + i) % 3],
                        kKinds[(i / 3) % 2], kBounds[(i * 3) % 5], i % 3 == 1,
                        i % 5 == 2};
    checkCase(c, uint32_t(100 + i));
    if (HasFatalFailure()) return;
  }
}

TEST(BoundPromise, PointwiseBoundsInRunsAtEveryScale) {
  // Where the sweep found blocks a float32 rounding over a pointwise bound as the reader evaluates
  // them (the encoder had measured its models in double).
  uint32_t seed = 500;
  for (const Index3 d : {Index3{1, 3, 2}, Index3{4, 3, 2}, Index3{4, 4, 4}, Index3{5, 4, 3}})
    for (const double scale : {1e-30, 1.0, 1e30})
      for (const Content content : {Content::Noise, Content::Smooth})
        for (const double bound : {1e-3, 1e-5})
          checkCase(PromiseCase{d, scale, content, BoundKind::MaxError, bound, false, true},
                    seed++);
}

TEST(BoundPromiseSlow, EveryCombination) {
  const std::vector<Index3> shapes = smallShapes();
  uint32_t seed = 1000;
  for (const Index3& d : shapes)
    for (const double scale : kScales)
      for (const Content content : kContents)
        for (const BoundKind kind : kKinds)
          for (const double bound : kBounds)
            for (const bool missing : {false, true}) {  // one volume, or a run: in turn
              const bool run = (seed & 3) >= 2;
              checkCase(PromiseCase{d, scale, content, kind, bound, missing, run}, seed++);
              if (HasFatalFailure()) return;
            }
}

TEST(BoundPromise, ShapesTheFormatCannotHoldAreRefusedByAxis) {
  std::vector<float> v(4 * 5 * 6, 1.0f);
  ArraySource src(v.data(), {4, 5, 6}, "v");
  EncoderOptions opt;
  opt.errorBound = 1e-3;
  opt.blocksPerAxis = 8;  // no axis holds 8 blocks: at most 5, along z
  const std::string path = afam_test::scratchPath("refused.afam");
  try {
    encodeVolume(src, opt, path);
    ADD_FAILURE() << "8 blocks per axis of a 4x5x6 volume were encoded";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("axis, z, has 6 samples"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(path));
  opt.blocksPerAxis = 5;  // the most z holds; x and y take fewer
  EXPECT_NO_THROW(encodeVolume(src, opt, path));
  std::filesystem::remove(path);
  try {
    ArraySource empty(v.data(), {4, 0, 6}, "v");
    ADD_FAILURE() << "a volume with an axis of 0 samples was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("axis y has 0 samples"), std::string::npos) << e.what();
  }
}
