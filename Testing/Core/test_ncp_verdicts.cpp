// SPDX-License-Identifier: BSD-3-Clause
// The NCP searches asked ahead (ncp_verdicts.hpp) of batched least-squares residuals
// (least_squares_batch.hpp): the CPU reference's residuals are the fitter's, on every shape; an
// encode whose searches are asked ahead writes the same file bit for bit with a fraction of the
// fits; a batch whose verdicts are wrong (every NCP passes) still gives the same file, its searches
// done again by fitting; and a residual too close to the bound to tell leaves the fit to decide.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <random>
#include <vector>

#include "afam/encode/encoder.hpp"
#include "afam/sampling/level_sampler.hpp"
#include "afam/search/least_squares_batch.hpp"
#include "afam/search/ncp_verdicts.hpp"
#include "afam/spline/fit.hpp"
#include "afam/volume/marschner_lobb.hpp"
#include "file_bytes.hpp"
#include "head_mri.hpp"
#include "noisy_block.hpp"
#include "scratch_dir.hpp"

using namespace afam;
using afam_test::smoothPlusNoise;

namespace {

/// Every NCP passes: a batch whose verdicts are wrong.
class EverythingPasses final : public LeastSquaresBatch {
 public:
  void setBlocks(const std::vector<const float*>&, const std::vector<Int3>&, int) override {}
  void residuals(const std::vector<LsqRequest>& requests, std::vector<LsqResidual>& out) override {
    out.assign(requests.size(), LsqResidual{1.0, 0.0});
  }
  std::string description() const override { return "liar"; }
};

/// A device that fails at its third batch of questions.
class FailsOnTheThirdCall final : public LeastSquaresBatch {
 public:
  void setBlocks(const std::vector<const float*>& s, const std::vector<Int3>& n,
                 int degree) override {
    cpu_.setBlocks(s, n, degree);
  }
  void residuals(const std::vector<LsqRequest>& requests, std::vector<LsqResidual>& out) override {
    if (++calls_ == 3) throw Error("the device was lost");
    cpu_.residuals(requests, out);
  }
  std::string description() const override { return "failing"; }

 private:
  CpuLeastSquaresBatch cpu_;
  int calls_ = 0;
};

/// The CPU reference, saying it answers `atOnce` requests at a time (a GPU's multiprocessors).
class Wide final : public LeastSquaresBatch {
 public:
  explicit Wide(int64_t atOnce) : atOnce_(atOnce) {}
  void setBlocks(const std::vector<const float*>& s, const std::vector<Int3>& n,
                 int degree) override {
    cpu_.setBlocks(s, n, degree);
  }
  void residuals(const std::vector<LsqRequest>& requests, std::vector<LsqResidual>& out) override {
    cpu_.residuals(requests, out);
  }
  std::string description() const override { return "wide"; }
  int64_t requestsAtOnce() const override { return atOnce_; }

 private:
  CpuLeastSquaresBatch cpu_;
  int64_t atOnce_;
};

/// The CPU reference, checking that each block handed over as a box of the volume's copy
/// (setBlocksIn) holds the box's samples, float for float.
class BoxesChecked final : public LeastSquaresBatch {
 public:
  void setBlocks(const std::vector<const float*>& s, const std::vector<Int3>& n,
                 int degree) override {
    cpu_.setBlocks(s, n, degree);
  }
  void setBlocksIn(const VolumeBoxes& boxes, const std::vector<const float*>& s,
                   const std::vector<Int3>& n, int degree) override {
    const auto* copy = dynamic_cast<const CpuLevelSampler*>(boxes.copy);
    std::vector<float> box;
    for (size_t b = 0; b < n.size() && copy; ++b) {
      box.resize(size_t(n[b][0]) * size_t(n[b][1]) * size_t(n[b][2]));
      copy->box(boxes.origins.at(b), n[b], box.data());
      ++boxes_;
      mismatches_ += std::memcmp(box.data(), s[b], box.size() * sizeof(float)) != 0;
    }
    cpu_.setBlocksIn(boxes, s, n, degree);
  }
  void residuals(const std::vector<LsqRequest>& requests, std::vector<LsqResidual>& out) override {
    cpu_.residuals(requests, out);
  }
  std::string description() const override { return "boxes checked"; }
  int64_t boxes_ = 0, mismatches_ = 0;

 private:
  CpuLeastSquaresBatch cpu_;
};

struct Encoded {
  std::vector<char> bytes;
  EncodeStats stats;
};

Encoded encodeWith(const std::vector<float>& v, Int3 n, double bound,
                   std::shared_ptr<LeastSquaresBatch> batch,
                   std::shared_ptr<LevelSampler> sampler = nullptr) {
  ArraySource src(v.data(), {n[0], n[1], n[2]}, "v");
  EncoderOptions opt;
  opt.errorBound = bound;
  opt.relativeBound = true;
  opt.threads = 2;
  opt.levels = 2;
  opt.blocksPerAxis = 4;  // blocks of 10-18 samples: many searches
  opt.leastSquares = std::move(batch);
  opt.levelSampler = std::move(sampler);
  const std::string path = afam_test::scratchPath("ahead.afam");
  Encoded e;
  e.stats = encodeVolume(src, opt, path);
  e.bytes = afam_test::readAll(path);
  std::remove(path.c_str());
  return e;
}

}  // namespace

TEST(LeastSquaresBatch, TheReferenceGivesTheFittersResiduals) {
  CpuLeastSquaresBatch batch;
  BlockFitter fitter;
  const std::vector<Int3> shapes{{8, 9, 10}, {33, 20, 17}, {1, 12, 9}, {2, 7, 30}, {64, 64, 5}};
  for (int degree : {1, 2, 3}) {
    std::vector<std::vector<float>> blocks;
    std::vector<const float*> pointers;
    for (size_t b = 0; b < shapes.size(); ++b) {
      blocks.push_back(smoothPlusNoise(shapes[b], 0.5, uint32_t(b)));
      pointers.push_back(blocks.back().data());
    }
    batch.setBlocks(pointers, shapes, degree);
    std::vector<LsqRequest> requests;
    for (size_t b = 0; b < shapes.size(); ++b) {
      Int3 degs{};
      for (int a = 0; a < 3; ++a) degs[a] = effectiveDegree(degree, shapes[b][a]);
      for (int k : {2, 4, 7, 64}) requests.push_back({int32_t(b), clampNcp(k, shapes[b], degs)});
    }
    std::vector<LsqResidual> got;
    batch.residuals(requests, got);
    ASSERT_EQ(got.size(), requests.size());
    for (size_t r = 0; r < requests.size(); ++r) {
      const Int3 n = shapes[size_t(requests[r].block)];
      const FitResult fit =
          fitter.fit(blocks[size_t(requests[r].block)].data(), n, requests[r].ncp, degree);
      const double count = double(n[0]) * n[1] * n[2];
      const double fitted = fit.error.rmse * fit.error.rmse * count;  // float32 points: a bit more
      SCOPED_TRACE(testing::Message() << "degree " << degree << " shape " << n[0] << "x" << n[1]
                                      << "x" << n[2] << " ncp " << requests[r].ncp[0] << ","
                                      << requests[r].ncp[1] << "," << requests[r].ncp[2]);
      EXPECT_GE(got[r].residual, -1e-9 * got[r].squares);
      EXPECT_NEAR(got[r].residual, fitted, 1e-6 * fitted + 1e-9 * got[r].squares);
      EXPECT_LE(got[r].residual, fitted * (1 + 1e-12) + 1e-9 * got[r].squares)
          << "least squares is the least";
    }
  }
}

TEST(LeastSquaresBatch, VerdictsAreCertainOnlyBeyondRounding) {
  const LsqResidual below{1e6, 0.999 * 100}, above{1e6, 1.001 * 100}, at{1e6, 100};
  EXPECT_EQ(lsqVerdict(below, 100, 1.0), Verdict::Passes);
  EXPECT_EQ(lsqVerdict(above, 100, 1.0), Verdict::Fails);
  EXPECT_EQ(lsqVerdict(at, 100, 1.0), Verdict::Unknown);
}

TEST(NcpVerdicts, AskedAheadTheEncoderWritesTheSameFileWithAFractionOfTheFits) {
  struct Volume {
    const char* name;
    std::vector<float> values;
    Int3 n;
    double bound;
  };
  std::vector<Volume> volumes;
  volumes.push_back({"head MRI", afam_test::headMri(), {48, 62, 42}, 1e-2});
  volumes.push_back(
      {"smooth plus noise", smoothPlusNoise({70, 60, 50}, 2.0, 7), {70, 60, 50}, 1e-2});
  std::vector<float> ml(size_t(41) * 41 * 41);
  marschnerLobbSlab(MarschnerLobb{}, {41, 41, 41}, 0, 41, ml.data());
  volumes.push_back({"Marschner-Lobb", ml, {41, 41, 41}, 1e-3});
  for (const Volume& v : volumes) {
    SCOPED_TRACE(v.name);
    const Encoded plain = encodeWith(v.values, v.n, v.bound, nullptr);
    const Encoded ahead =
        encodeWith(v.values, v.n, v.bound, std::make_shared<CpuLeastSquaresBatch>());
    const Encoded lied = encodeWith(v.values, v.n, v.bound, std::make_shared<EverythingPasses>());
    std::printf(
        "[ahead] %s: fits %lld plain, %lld asked ahead (%lld residuals), %lld with wrong "
        "verdicts; %zu bytes\n",
        v.name, (long long)plain.stats.fits, (long long)ahead.stats.fits,
        (long long)ahead.stats.askedAhead, (long long)lied.stats.fits, plain.bytes.size());
    EXPECT_TRUE(ahead.bytes == plain.bytes) << "asked ahead, the file differs";
    EXPECT_TRUE(lied.bytes == plain.bytes) << "with wrong verdicts, the file differs";
    EXPECT_GT(ahead.stats.askedAhead, 0);
    EXPECT_LT(2 * ahead.stats.fits, plain.stats.fits);
  }
}

TEST(NcpVerdicts, ADeviceThatFailsMidEncodeLeavesTheRestToTheFits) {
  const std::vector<float> v = afam_test::headMri();
  const Encoded plain = encodeWith(v, {48, 62, 42}, 1e-2, nullptr);
  const Encoded failed = encodeWith(v, {48, 62, 42}, 1e-2, std::make_shared<FailsOnTheThirdCall>());
  EXPECT_TRUE(failed.bytes == plain.bytes) << "the file differs after the device failed";
  EXPECT_NE(failed.stats.aheadFailure.find("the device was lost"), std::string::npos)
      << "'" << failed.stats.aheadFailure << "'";
  EXPECT_TRUE(plain.stats.aheadFailure.empty());
}

TEST(NcpVerdicts, QuestionsAskedAheadOfTheirTurnGiveTheSameVerdictsInFewerRounds) {
  std::vector<std::vector<float>> values;
  std::vector<Int3> shapes{{20, 18, 16}, {17, 17, 17}, {24, 10, 14}, {16, 16, 16}, {9, 30, 12}};
  for (size_t b = 0; b < shapes.size(); ++b)
    values.push_back(smoothPlusNoise(shapes[b], 0.05 + 0.1 * double(b), uint32_t(b + 3)));
  const SearchSettings settings{2, 0.08, SearchMethod::Fast, 2, true};
  std::vector<NcpVerdicts> narrow(shapes.size()), wide(shapes.size());
  const auto ask = [&](std::vector<NcpVerdicts>& out, int64_t atOnce) {
    std::vector<AheadBlock> blocks;
    for (size_t b = 0; b < shapes.size(); ++b)
      blocks.push_back(
          {values[b].data(), shapes[b], &out[b], std::nullopt, std::nullopt, std::nullopt});
    CpuLeastSquaresBatch batch;
    return askAhead(batch, blocks, settings, atOnce);
  };
  const AheadStats one = ask(narrow, 1), many = ask(wide, 64);
  std::printf("[ahead] one at a time: %lld rounds, %lld residuals; 64 at once: %lld, %lld\n",
              (long long)one.rounds, (long long)one.requests, (long long)many.rounds,
              (long long)many.requests);
  EXPECT_LE(2 * many.rounds, one.rounds + 1);
  EXPECT_GT(many.requests, one.requests);
  for (size_t b = 0; b < shapes.size(); ++b)
    for (const auto& [ncp, v] : narrow[b].known) {
      SCOPED_TRACE(testing::Message()
                   << "block " << b << " ncp " << ncp[0] << "," << ncp[1] << "," << ncp[2]);
      EXPECT_EQ(wide[b].of(ncp), v) << "asked ahead of its turn, a verdict differs or is missing";
    }
  // The encoder's searches consult only those: the same file with the same fits.
  const std::vector<float> head = afam_test::headMri();
  const Encoded plain = encodeWith(head, {48, 62, 42}, 1e-2, std::make_shared<Wide>(1));
  const Encoded wider = encodeWith(head, {48, 62, 42}, 1e-2, std::make_shared<Wide>(96));
  EXPECT_TRUE(wider.bytes == plain.bytes) << "asked ahead of their turn, the file differs";
  EXPECT_EQ(wider.stats.fits, plain.stats.fits);
  int64_t roundsPlain = 0, roundsWider = 0;
  for (const LevelStats& ls : plain.stats.levels) roundsPlain += ls.aheadRounds;
  for (const LevelStats& ls : wider.stats.levels) roundsWider += ls.aheadRounds;
  std::printf("[ahead] head MRI: rounds %lld one at a time, %lld 96 at once\n",
              (long long)roundsPlain, (long long)roundsWider);
  EXPECT_LT(3 * roundsWider, 2 * roundsPlain);
}

TEST(NcpVerdicts, TheFinestBlocksAreAskedAsBoxesOfTheVolumesCopyWithTheirOwnSamples) {
  const std::vector<float> head = afam_test::headMri();
  const Encoded plain = encodeWith(head, {48, 62, 42}, 1e-2, nullptr);
  auto checked = std::make_shared<BoxesChecked>();
  const Encoded boxed =
      encodeWith(head, {48, 62, 42}, 1e-2, checked, std::make_shared<CpuLevelSampler>());
  std::printf("[ahead] head MRI: %lld finest blocks asked as boxes of the copy\n",
              (long long)checked->boxes_);
  EXPECT_EQ(checked->boxes_, 4 * 4 * 4) << "every finest block (the level sampler held the volume)";
  EXPECT_EQ(checked->mismatches_, 0) << "a box of the copy is not its block's samples";
  EXPECT_TRUE(boxed.bytes == plain.bytes) << "asked from the copy, the file differs";
  EXPECT_LT(2 * boxed.stats.fits, plain.stats.fits);
}
