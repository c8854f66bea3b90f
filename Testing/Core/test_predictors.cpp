// SPDX-License-Identifier: BSD-3-Clause
// Prefetch predictors: LSTM forward pass against torch's output for the shipped weights,
// the held-out path bar (LSTM below linear extrapolation on generated walks), APPA table against a
// brute-force visibility computation, its cache file (round trip, stale and corrupt files rebuilt),
// ForeCache's Markov chain on a known pattern and its phase switch.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <fstream>
#include <random>
#include <set>

#include "afam/errors.hpp"
#include "afam/lod.hpp"
#include "afam/predictors/appa.hpp"
#include "afam/predictors/forecache.hpp"
#include "afam/predictors/lstm.hpp"
#include "afam/predictors/pose_predictor.hpp"
#include "afam/predictors/prefetch_predictors.hpp"
#include "afam/trajectory_gen.hpp"
#include "afam/transfer_function.hpp"
#include "render_test_util.hpp"
#include "scratch_dir.hpp"

using namespace afam;

namespace {

std::string tmp(const std::string& stem) {
  return afam_test::scratchPath(stem);
}

std::vector<unsigned char> slurp(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return std::vector<unsigned char>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
void spit(const std::string& p, const std::vector<unsigned char>& b) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
}

double meanError(PosePredictor& p, const std::vector<Pose>& poses) {
  p.reset();
  double e = 0;
  for (std::size_t i = 0; i + 1 < poses.size(); ++i) {
    p.observe(poses[i]);
    e += poseDistance(p.predictNext(), poses[i + 1]);
  }
  return e / double(poses.size() - 1);
}

}  // namespace

// ---------------------------------------------------------------------------------------- poses

TEST(Predictors, PosePositionRoundTripAndTrajectoryFile) {
  const Pose p{1.3, 37.0, 251.0};
  const Pose q = poseFromPosition(posePosition(p));
  EXPECT_NEAR(q.distance, 1.3, 1e-12);
  EXPECT_NEAR(q.thetaDeg, 37.0, 1e-9);
  EXPECT_NEAR(q.phiDeg, 251.0, 1e-9);
  const std::string path = tmp("traj.dat");
  writeTrajectory(path, {p, Pose{1.0, 90.0, 0.0}});
  const auto back = loadTrajectory(path);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_NEAR(back[0].phiDeg, 251.0, 1e-4);
  EXPECT_NEAR(back[1].thetaDeg, 90.0, 1e-5);
  std::remove(path.c_str());
  EXPECT_THROW(makePosePredictor("oracle"), InvalidArgument);
}

TEST(Predictors, LinearExtrapolatesPositions) {
  LinearPosePredictor lin;
  lin.observe(poseFromPosition({1.0, 0.0, 0.0}));
  lin.observe(poseFromPosition({1.0, 0.1, 0.0}));
  const Vec3 n = posePosition(lin.predictNext());
  EXPECT_NEAR(n[0], 1.0, 1e-9);
  EXPECT_NEAR(n[1], 0.2, 1e-9);
  EXPECT_NEAR(n[2], 0.0, 1e-9);
}

// ----------------------------------------------------------------------------------------- LSTM

TEST(Predictors, LstmForwardMatchesTorch) {
  const LstmWeights w = loadLstmWeights(defaultLstmWeightsPath());
  ASSERT_GT(w.testSteps, 0u);
  const std::vector<float> out = lstmForward(w, w.testInput.data(), int(w.testSteps));
  ASSERT_EQ(out.size(), w.testOutput.size());
  for (std::size_t k = 0; k < out.size(); ++k)
    EXPECT_NEAR(out[k], w.testOutput[k], 1e-5f + 1e-5f * std::fabs(w.testOutput[k])) << "output " << k;
}

TEST(Predictors, LstmWeightsFileRejectsDamage) {
  const std::string good = defaultLstmWeightsPath();
  EXPECT_THROW(loadLstmWeights(tmp("missing.bin")), IoError);
  auto bytes = slurp(good);
  ASSERT_GT(bytes.size(), 100u);
  const std::string bad = tmp("bad_lstm.bin");
  auto flipped = bytes;
  flipped[200] ^= 0x40;  // a weight
  spit(bad, flipped);
  EXPECT_THROW(loadLstmWeights(bad), FormatError);
  auto truncated = bytes;
  truncated.resize(bytes.size() / 2);
  spit(bad, truncated);
  EXPECT_THROW(loadLstmWeights(bad), FormatError);
  auto magic = bytes;
  magic[0] = 'X';
  spit(bad, magic);
  EXPECT_THROW(loadLstmWeights(bad), FormatError);
  std::remove(bad.c_str());
}

// The bar: on exploration paths the weights never saw, the LSTM's next-pose error is below last-pose
// linear extrapolation's (both in Cartesian eye positions, as `afam predict` measures them). The
// paths are generated walks (trajectory_gen.hpp); with AFAM_TRAJECTORIES naming a folder of
// recorded paths, its held-out user_2.dat is used instead.
TEST(Predictors, LstmBeatsLinearOnHeldOutPaths) {
  std::vector<std::vector<Pose>> paths;
  const char* recorded = std::getenv("AFAM_TRAJECTORIES");
  if (recorded && *recorded) paths.push_back(loadTrajectory(std::string(recorded) + "/user_2.dat"));
  else
    for (uint64_t seed : {101, 202, 303}) paths.push_back(explorationWalk(400, seed));
  for (const auto& poses : paths) {
    LinearPosePredictor lin;
    LstmPosePredictor lstm(defaultLstmWeightsPath());
    const double eLin = meanError(lin, poses), eLstm = meanError(lstm, poses);
    RecordProperty("linear", std::to_string(eLin));
    RecordProperty("lstm", std::to_string(eLstm));
    EXPECT_LT(eLstm, eLin);
  }
}

// ----------------------------------------------------------------------------------------- APPA

namespace {
// A visibility function with structure: depends on the quantised pose only through the sample pose.
std::vector<int64_t> fakeVisible(const Pose& p) {
  std::vector<int64_t> v;
  const int base = int(p.thetaDeg * 7 + p.phiDeg * 3 + p.distance * 100);
  for (int k = 0; k < 5 + int(p.phiDeg) % 7; ++k) v.push_back((base + 13 * k) % 4096);
  return v;
}
}  // namespace

TEST(Predictors, AppaGridQuantisesLikeTheAuthors) {
  AppaGrid g;
  g.sample = AppaGrid::Sample::Corner;
  EXPECT_EQ(g.distanceCells(), 10);
  EXPECT_EQ(g.thetaCells(), 30);
  EXPECT_EQ(g.phiCells(), 60);
  const Pose parent = g.samplePose(g.cellOf(Pose{1.37, 44.0, 359.9}));
  EXPECT_NEAR(parent.distance, 1.3, 1e-9);
  EXPECT_NEAR(parent.thetaDeg, 42.0, 1e-9);
  EXPECT_NEAR(parent.phiDeg, 354.0, 1e-9);
  // below dMin and beyond dMax clamp; phi wraps
  EXPECT_EQ(g.cellOf(Pose{0.5, 10, 370}), g.cellOf(Pose{1.0, 10, 10}));
  EXPECT_EQ(g.cellOf(Pose{2.5, 10, -350}), g.cellOf(Pose{1.95, 10, 10}));
}

TEST(Predictors, AppaTableRoundTripStaleAndCorrupt) {
  AppaGrid g;
  g.dMax = 1.3;  // small grid: 3 x 30 x 60 cells
  const AppaTable t = AppaTable::build(g, fakeVisible, 2);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> d(0.9, 1.4), th(0, 180), ph(0, 360);
  for (int i = 0; i < 200; ++i) {
    const Pose p{d(rng), th(rng), ph(rng)};
    EXPECT_EQ(t.blocks(p), fakeVisible(g.samplePose(g.cellOf(p))));
  }
  const std::string path = tmp("t.afam.appa");
  AppaTable keyed = t;
  keyed.setKey(42);
  keyed.save(path);
  const AppaTable back = AppaTable::load(path);
  EXPECT_EQ(back.key(), 42u);
  EXPECT_EQ(back.entryCount(), t.entryCount());
  EXPECT_EQ(back.blocks(Pose{1.15, 33, 100}), t.blocks(Pose{1.15, 33, 100}));

  int calls = 0;
  auto counting = [&calls](const Pose& p) { ++calls; return fakeVisible(p); };
  AppaBuildReport rep;
  AppaTable::loadOrBuild(path, 42, g, counting, &rep);
  EXPECT_TRUE(rep.loadedFromCache);
  EXPECT_EQ(calls, 0);
  EXPECT_GT(rep.bytes, 0u);

  AppaTable::loadOrBuild(path, 43, g, counting, &rep);  // stale: another .afam / settings
  EXPECT_FALSE(rep.loadedFromCache);
  EXPECT_NE(rep.rebuiltBecause.find("stale"), std::string::npos);
  EXPECT_EQ(calls, g.cellCount());
  EXPECT_EQ(AppaTable::load(path).key(), 43u);  // rewritten

  auto bytes = slurp(path);
  bytes[bytes.size() / 2] ^= 1;
  spit(path, bytes);
  EXPECT_THROW(AppaTable::load(path), FormatError);
  calls = 0;
  AppaTable::loadOrBuild(path, 43, g, counting, &rep);
  EXPECT_FALSE(rep.loadedFromCache);
  EXPECT_NE(rep.rebuiltBecause.find("checksum"), std::string::npos);
  EXPECT_EQ(calls, g.cellCount());
  bytes = slurp(path);
  bytes.resize(40);
  spit(path, bytes);
  EXPECT_THROW(AppaTable::load(path), FormatError);
  std::remove(path.c_str());
}

// The table stores what a brute-force visibility computation gives at each cell's sample pose:
// every block of the LOD cut whose box is not entirely outside the frustum (no TF culling here).
TEST(Predictors, AppaTableMatchesBruteForceVisibility) {
  auto file = afam_test::encodeMl(33, EncodingMode::Adaptive, 3, 4);
  LodOptions lo;
  lo.tfCulling = false;
  const LodSelector sel(lo);
  AppaGrid g;
  g.dMax = 1.2;
  g.angleStep = 30;  // coarse: brute force over every cell stays cheap
  const auto visible = makeLodVisibleFn(file, sel, 64, 64, {}, 0.0, 1.0);
  const AppaTable t = AppaTable::build(g, visible);
  for (int c = 0; c < g.cellCount(); ++c) {
    const Pose p = g.samplePose(c);
    const Camera cam = Camera::fromPose(p, 64, 64);
    std::set<int64_t> brute;
    for (const BlockRef& b : sel.cut(file->partition(), cam)) {
      double blo[3], bhi[3];
      blockBox(file->partition(), b.level, b.ijk, blo, bhi);
      if (!LodSelector::outsideFrustum(cam, blo, bhi)) brute.insert(file->entryIndex(b.level, b.ijk));
    }
    const auto got = t.blocks(p);
    EXPECT_EQ(std::set<int64_t>(got.begin(), got.end()), brute) << "cell " << c;
    EXPECT_EQ(got.size(), brute.size());
    // importance order: nearest block centre first
    const Vec3 eye = posePosition(p);
    double prev = -1;
    for (int64_t e : got) {
      const ModelEntry& me = file->entries()[std::size_t(e)];
      double blo[3], bhi[3];
      blockBox(file->partition(), me.level, me.block, blo, bhi);
      double d2 = 0;
      for (int k = 0; k < 3; ++k) d2 += std::pow(0.5 * (blo[k] + bhi[k]) - eye[k], 2);
      EXPECT_GE(d2, prev - 1e-12);
      prev = d2;
    }
  }
}

// ------------------------------------------------------------------------------------ ForeCache

TEST(Predictors, ForeCacheMovesRoundTrip) {
  const Pose a{1.2, 70, 30};
  const CameraMove m{3.0, -4.0, 0.05};
  const Pose b = ForeCacheMarkov::applyMove(a, m);
  const CameraMove back = ForeCacheMarkov::moveBetween(a, b);
  EXPECT_NEAR(back.dTheta, 3.0, 1e-6);
  EXPECT_NEAR(back.dPhi, -4.0, 1e-6);
  EXPECT_NEAR(back.dDistance, 0.05, 1e-9);
}

// A path with a known pattern: two slow steps along +theta, then one fast step along +phi, again
// and again. An order-3 chain learns it exactly; a first-order chain cannot (after a theta step
// both theta and phi follow).
TEST(Predictors, ForeCacheMarkovLearnsAKnownPattern) {
  const CameraMove pattern[3] = {{2.0, 0, 0}, {2.0, 0, 0}, {0, 7.0, 0}};
  ForeCacheMarkov chain;
  int correct = 0, total = 0;
  for (int i = 0; i < 60; ++i) {
    const CameraMove& m = pattern[i % 3];
    if (i >= 30) {
      ++total;
      correct += chain.predictSymbol() == chain.symbolOf(m);
    }
    chain.observeMove(m);
  }
  EXPECT_EQ(correct, total);
  // and the pose prediction lands on the next pose of the pattern
  ForeCachePosePredictor fc;
  Pose p{1.3, 60, 10};
  double err = 0;
  int n = 0;
  for (int i = 0; i < 45; ++i) {
    fc.observe(p);
    const Pose next = ForeCacheMarkov::applyMove(p, pattern[i % 3]);
    if (i >= 30) {
      err += poseDistance(fc.predictNext(), next);
      ++n;
    }
    p = next;
  }
  EXPECT_LT(err / n, 1e-6);
}

TEST(Predictors, ForeCachePhaseSwitch) {
  ForeCachePosePredictor fc;
  Pose p{1.2, 80, 0};
  // navigating: steady 4-degree steps in one direction
  for (int i = 0; i < 10; ++i) {
    fc.observe(p);
    p = ForeCacheMarkov::applyMove(p, {0, 4.0, 0});
  }
  EXPECT_EQ(fc.phase(), ForeCachePhase::Navigation);
  // sensemaking: small back-and-forth moves around one region
  for (int i = 0; i < 10; ++i) {
    fc.observe(p);
    p = ForeCacheMarkov::applyMove(p, {i % 2 ? 0.8 : -0.8, 0.3, 0});
  }
  EXPECT_EQ(fc.phase(), ForeCachePhase::Sensemaking);
  // foraging: zoomed out and sweeping
  p.distance = 1.8;
  for (int i = 0; i < 10; ++i) {
    fc.observe(p);
    p = ForeCacheMarkov::applyMove(p, {5.0, 0, 0});
  }
  EXPECT_EQ(fc.phase(), ForeCachePhase::Foraging);
}

// In Sensemaking the SB model picks, among the Markov candidates, the view whose blocks look like
// what the user dwelt on (here: block ids as signatures, views toward +phi show "similar" data).
TEST(Predictors, ForeCacheSignatureModelPicksSimilarView) {
  ForeCacheDataSource data;
  data.visibleBlocks = [](const Pose& p) { return std::vector<int64_t>{int64_t(std::floor(p.phiDeg))}; };
  data.signature = [](int64_t b) { return BlockSignature{float(b) / 360.f, 0, 0, 0}; };
  ForeCachePosePredictor fc({}, data);
  Pose p{1.2, 90, 100};
  for (int i = 0; i < 12; ++i) {  // dwell around phi = 100 with small theta wiggles
    fc.observe(p);
    p = ForeCacheMarkov::applyMove(p, {i % 2 ? 1.0 : -1.0, 0, 0});
  }
  ASSERT_EQ(fc.phase(), ForeCachePhase::Sensemaking);
  const Pose next = fc.predictNext();
  EXPECT_NEAR(next.phiDeg, 100.0, 1.0);  // stays on the dwelt data
}
