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

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "bound_promise_cases.hpp"
#include "decoded_bound.hpp"
#include "scratch_dir.hpp"

using namespace afam;
using namespace afam_test;

namespace {

bool checkCase(const PromiseCase& c, uint32_t seed) {
  SCOPED_TRACE(c.name());
  const std::string path = afam_test::scratchPath("promise.afam");
  const afam_test::EncodedCase e = afam_test::encodeCase(c, seed, afam_test::optionsOf(c), path);
  if (e.refused) {
    std::printf("refused: %s: %s\n", c.name().c_str(), e.error.c_str());
    return false;  // refused, by name
  }
  for (size_t step = 0; step < e.sources.size(); ++step) {
    SCOPED_TRACE("step " + std::to_string(step));
    auto f = AfamFile::open(path, int64_t(step));
    afam_test::expectEveryBlockWithinItsBound(*f, *e.sources[step]);
  }
  std::filesystem::remove(path);
  return true;
}

}  // namespace

TEST(BoundPromise, TheTwoByTwoByTwoVolumeThatDecodedTo1e24) {
  // Standard normal values whose interpolant with rounded points at 1e-3 codes into exactly the
  // 32 bytes of its float32 samples: a reader took the coded bytes for floats.
  std::vector<float> v = afam_test::theVolumeThatDecodedTo1e24();
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

TEST(BoundPromise, TwoByTwoByTwoNoiseAtEveryBound) { afam_test::forEachTwoByTwoCase(checkCase); }

TEST(BoundPromise, EverySmallShapeWithRotatingSettings) {
  afam_test::forEachRotatingShapeCase([&](const PromiseCase& c, uint32_t seed) {
    if (!HasFatalFailure()) checkCase(c, seed);
  });
}

TEST(BoundPromise, PointwiseBoundsInRunsAtEveryScale) {
  afam_test::forEachPointwiseRunCase(checkCase);
}

/// Every combination of the sweep with its seed, until visit returns false.
template <typename Visit>
void forEachSweepCase(Visit&& visit) {
  const std::vector<Index3> shapes = smallShapes();
  uint32_t seed = 1000;
  for (const Index3& d : shapes)
    for (const double scale : kScales)
      for (const Content content : kContents)
        for (const BoundKind kind : kKinds)
          for (const double bound : kBounds)
            for (const bool missing : {false, true}) {  // one volume, or a run: in turn
              const bool run = (seed & 3) >= 2;
              if (!visit(PromiseCase{d, scale, content, kind, bound, missing, run}, seed++)) return;
            }
}

TEST(BoundPromiseSlow, EveryCombination) {
  forEachSweepCase([&](const PromiseCase& c, uint32_t seed) {
    checkCase(c, seed);
    return !HasFatalFailure();
  });
}

TEST(BoundPromise, TheSweepsPointwiseInterpolantsOverTheBoundAsRead) {
  // The sweep's cases (with its seeds) where interpolants measured by the fitter within a
  // pointwise bound were 0.01-0.1% over it as the reader decodes them (every one a noise block at
  // a bound of 1e-5 or 1e-4, most at the extreme scales, most in runs).
  const std::vector<std::string> cases = {"1x3x2 noise scale 1e+30 max_error 1e-05 run",
                                          "4x4x4 noise scale 1e+30 max_error 1e-05 run",
                                          "5x5x5 noise scale 1e-30 max_error 1e-05 run",
                                          "1x64x64 noise scale 1e+30 max_error 1e-05 run",
                                          "2x64x64 noise scale 1e-30 max_error 1e-05 run",
                                          "64x2x64 noise scale 1e+10 max_error 0.0001",
                                          "64x64x2 noise scale 1 max_error 1e-05 run"};
  size_t checked = 0;
  forEachSweepCase([&](const PromiseCase& c, uint32_t seed) {
    if (std::find(cases.begin(), cases.end(), c.name()) != cases.end())
      checked += checkCase(c, seed);
    return !HasFatalFailure();
  });
  EXPECT_EQ(checked, cases.size());
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
