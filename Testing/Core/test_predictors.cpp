// SPDX-License-Identifier: BSD-3-Clause
// Prefetch predictors, all built by makePrefetchPredictor and fed camera histories: linear
// extrapolation, LSTM forward pass against torch's output for the shipped weights, the held-out
// path bar (LSTM below linear extrapolation on generated walks), APPA table against a brute-force
// visibility computation, its cache file (round trip, stale and corrupt files rebuilt), ForeCache's
// Markov chain on a known pattern, its phase switch, and its history alignment.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <set>

#include "afam/base/errors.hpp"
#include "afam/predict/appa.hpp"
#include "afam/predict/forecache.hpp"
#include "afam/predict/lstm.hpp"
#include "afam/predict/predictor_factory.hpp"
#include "afam/scene/lod.hpp"
#include "afam/scene/trajectory_gen.hpp"
#include "afam/scene/transfer_function.hpp"
#include "render_test_util.hpp"
#include "scratch_dir.hpp"

using namespace afam;

namespace {

std::string tmp(const std::string& stem) { return afam_test::scratchPath(stem); }

std::vector<unsigned char> slurp(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return std::vector<unsigned char>((std::istreambuf_iterator<char>(in)),
                                    std::istreambuf_iterator<char>());
}
void spit(const std::string& p, const std::vector<unsigned char>& b) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
}

// Mean distance between the predicted and the actual next eye over a trajectory, scored as
// `afam predict` scores it.
double meanError(const Predictor& p, const std::vector<Pose>& poses) {
  std::vector<Camera> history;
  double e = 0;
  for (std::size_t i = 0; i + 1 < poses.size(); ++i)
    e += poseDistance(predictNextPose(p, history, poses[i]), poses[i + 1]);
  return e / double(poses.size() - 1);
}

std::vector<Camera> camerasOf(const std::vector<Pose>& poses) {
  std::vector<Camera> c;
  for (const Pose& p : poses) c.push_back(Camera::fromPose(p, 32, 32));
  return c;
}

}  // namespace

// ---------------------------------------------------------------------------------------- poses

TEST(Predictors, PosePositionRoundTripAndTrajectoryFile) {
  const Pose p{1.3, 37.0, 251.0};
  const Pose q = poseFromPosition(posePosition(p));
  EXPECT_NEAR(q.distance, 1.3, 1e-12);
  EXPECT_NEAR(q.thetaDeg, 37.0, 1e-9);
  EXPECT_NEAR(q.phiDeg, 251.0, 1e-9);
  const Vec3 eye = Camera::fromPose(p, 8, 8).eye;  // one formula: bit for bit the camera's eye
  for (int a = 0; a < 3; ++a) EXPECT_EQ(posePosition(p)[a], eye[a]) << "axis " << a;
  const std::string path = tmp("traj.dat");
  writeTrajectory(path, {p, Pose{1.0, 90.0, 0.0}});
  const auto back = loadTrajectory(path);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_NEAR(back[0].phiDeg, 251.0, 1e-4);
  EXPECT_NEAR(back[1].thetaDeg, 90.0, 1e-5);
  std::remove(path.c_str());
  try {
    writeTrajectory(tmp("no/such/folder/traj.dat"), {p});
    ADD_FAILURE() << "writing into a missing folder did not throw";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("trajectory"), std::string::npos) << e.what();
  }
}

TEST(Predictors, OneFactoryBuildsEveryName) {
  for (const std::string& name : predictorNames())
    EXPECT_EQ(std::string(makePrefetchPredictor(name)->name()), name);
  EXPECT_THROW(makePrefetchPredictor("oracle"), InvalidArgument);
  PredictorContext missingWeights;
  missingWeights.lstmWeights = tmp("no_weights.bin");
  EXPECT_THROW(makePrefetchPredictor("lstm", missingWeights), IoError);
}

TEST(Predictors, NoneStaysAndLinearExtrapolatesPositions) {
  const auto none = makePrefetchPredictor("none"), linear = makePrefetchPredictor("linear");
  std::vector<Camera> h;
  const Pose a = poseFromPosition({1.0, 0.0, 0.0}), b = poseFromPosition({1.0, 0.1, 0.0});
  EXPECT_EQ(predictNextPose(*linear, h, a).phiDeg, a.phiDeg);  // one pose: no prediction, stay
  const Vec3 n = posePosition(predictNextPose(*linear, h, b));
  EXPECT_NEAR(n[0], 1.0, 1e-12);
  EXPECT_NEAR(n[1], 0.2, 1e-12);
  EXPECT_NEAR(n[2], 0.0, 1e-12);
  std::vector<Camera> h2;
  predictNextPose(*none, h2, a);
  const Pose stay = predictNextPose(*none, h2, b);
  EXPECT_EQ(stay.distance, b.distance);
  EXPECT_EQ(stay.phiDeg, b.phiDeg);
  // The history stays bounded like the renderer's.
  for (int i = 0; i < 40; ++i) predictNextPose(*none, h2, Pose{1.5, 60, double(i)});
  EXPECT_EQ(h2.size(), kPredictorHistory);
  EXPECT_NEAR(poseFromPosition(h2.back().eye).phiDeg, 39.0, 1e-9);
}

// ----------------------------------------------------------------------------------------- LSTM

TEST(Predictors, LstmForwardMatchesTorch) {
  const LstmWeights w = loadLstmWeights(defaultLstmWeightsPath());
  ASSERT_GT(w.testSteps, 0u);
  const std::vector<float> out = lstmForward(w, w.testInput.data(), int(w.testSteps));
  ASSERT_EQ(out.size(), w.testOutput.size());
  for (std::size_t k = 0; k < out.size(); ++k)
    EXPECT_NEAR(out[k], w.testOutput[k], 1e-5f + 1e-5f * std::fabs(w.testOutput[k]))
        << "output " << k;
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

// The bar: on exploration paths the weights never saw, the LSTM's next-pose error is below
// last-pose linear extrapolation's (both in Cartesian eye positions, as `afam predict` measures
// them). The paths are generated walks (trajectory_gen.hpp); with AFAM_TRAJECTORIES naming a folder
// of recorded paths, its held-out user_2.dat is used instead.
TEST(Predictors, LstmBeatsLinearOnHeldOutPaths) {
  std::vector<std::vector<Pose>> paths;
  const char* recorded = std::getenv("AFAM_TRAJECTORIES");
  if (recorded && *recorded)
    paths.push_back(loadTrajectory(std::string(recorded) + "/user_2.dat"));
  else
    for (uint64_t seed : {101, 202, 303}) paths.push_back(explorationWalk(400, seed));
  const auto lin = makePrefetchPredictor("linear"), lstm = makePrefetchPredictor("lstm");
  for (const auto& poses : paths) {
    const double eLin = meanError(*lin, poses), eLstm = meanError(*lstm, poses);
    RecordProperty("linear", std::to_string(eLin));
    RecordProperty("lstm", std::to_string(eLstm));
    EXPECT_LT(eLstm, eLin);
    EXPECT_GT(eLstm, 0.1 * eLin);  // a real prediction, not a copy of the next pose
  }
}

// The LSTM camera predictor is lstmNextPosition of the last window + 1 eyes: older cameras do not
// change it, and fewer than two make no prediction.
TEST(Predictors, LstmPredictsFromTheLastWindowOfEyes) {
  const LstmPredictor lstm(defaultLstmWeightsPath());
  const std::size_t window = lstm.weights().window;
  ASSERT_LT(window + 1, kPredictorHistory);
  const std::vector<Pose> walk = explorationWalk(int(window) + 6, 17);
  const std::vector<Camera> all = camerasOf(walk);
  Camera next;
  EXPECT_FALSE(lstm.predict({all.front()}, next));
  ASSERT_TRUE(lstm.predict(all, next));
  std::vector<Vec3> eyes;
  for (std::size_t i = all.size() - window - 1; i < all.size(); ++i) eyes.push_back(all[i].eye);
  const Vec3 expect = lstmNextPosition(lstm.weights(), eyes);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(next.eye[a], expect[a], 1e-12) << "axis " << a;
  Camera fromWindow;
  ASSERT_TRUE(
      lstm.predict(std::vector<Camera>(all.end() - long(window) - 1, all.end()), fromWindow));
  for (int a = 0; a < 3; ++a) EXPECT_EQ(fromWindow.eye[a], next.eye[a]);
  // The prediction is not the linear one (the head's correction is not zero).
  const Vec3 b = all.back().eye, c = all[all.size() - 2].eye;
  double d = 0;
  for (int a = 0; a < 3; ++a) d += std::fabs(expect[a] - (2 * b[a] - c[a]));
  EXPECT_GT(d, 1e-6);
  EXPECT_THROW(lstmNextPosition(lstm.weights(), {b}), InvalidArgument);
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

// A pose on a cell boundary (theta 60, phi 30: multiples of 6 degrees) keeps its cell after the
// round trip through a camera, which loses a few ulps; so does the predictor's parent POV.
TEST(Predictors, AppaCellSurvivesTheCameraRoundTrip) {
  const AppaGrid g;
  for (const Pose& p : {Pose{1.5, 60, 30}, Pose{1.2, 90, 0}, Pose{1.3, 30, 354}}) {
    const Pose back = poseFromPosition(Camera::fromPose(p, 8, 8).eye);
    EXPECT_EQ(g.cellOf(back), g.cellOf(p)) << p.distance << " " << p.thetaDeg << " " << p.phiDeg;
  }
  const auto appa = makePrefetchPredictor("appa");  // no file: parent POV, no blocks
  std::vector<Camera> h;
  const Pose parent = predictNextPose(*appa, h, Pose{1.5, 60, 30});
  EXPECT_NEAR(parent.distance, 1.55, 1e-9);
  EXPECT_NEAR(parent.thetaDeg, 63.0, 1e-9);
  EXPECT_NEAR(parent.phiDeg, 33.0, 1e-9);
  std::vector<int64_t> entries;
  EXPECT_FALSE(appa->predictEntries(h, entries));
  // With a table the predictor hands over the blocks the table stores for the last pose's cell.
  AppaGrid small;
  small.dMax = 1.3;
  const AppaPredictor withTable(AppaTable::build(small, fakeVisible));
  const std::vector<Camera> one = camerasOf({Pose{1.17, 44, 100}});
  ASSERT_TRUE(withTable.predictEntries(one, entries));
  EXPECT_EQ(entries, fakeVisible(small.samplePose(small.cellOf(Pose{1.17, 44, 100}))));
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
  auto counting = [&calls](const Pose& p) {
    ++calls;
    return fakeVisible(p);
  };
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
      if (!LodSelector::outsideFrustum(cam, blo, bhi))
        brute.insert(file->entryIndex(b.level, b.ijk));
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
  ForeCacheModel fc;
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
  ForeCacheModel fc;
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
  data.visibleBlocks = [](const Pose& p) {
    return std::vector<int64_t>{int64_t(std::floor(p.phiDeg))};
  };
  data.signature = [](int64_t b) { return BlockSignature{float(b) / 360.f, 0, 0, 0}; };
  ForeCacheModel fc({}, data);
  Pose p{1.2, 90, 100};
  for (int i = 0; i < 12; ++i) {  // dwell around phi = 100 with small theta wiggles
    fc.observe(p);
    p = ForeCacheMarkov::applyMove(p, {i % 2 ? 1.0 : -1.0, 0, 0});
  }
  ASSERT_EQ(fc.phase(), ForeCachePhase::Sensemaking);
  const Pose next = fc.predictNext();
  EXPECT_NEAR(next.phiDeg, 100.0, 1.0);  // stays on the dwelt data
}

// The forecache predictor fed the renderer's bounded, sliding camera history learns what the model
// fed every pose learns; a history that does not continue the previous one starts it over.
TEST(Predictors, ForeCachePredictorAlignsItsHistory) {
  const CameraMove pattern[3] = {{2.0, 0, 0}, {2.0, 0, 0}, {0, 7.0, 0}};
  std::vector<Pose> path = {Pose{1.3, 60, 10}};
  for (int i = 0; i < 44; ++i)
    path.push_back(ForeCacheMarkov::applyMove(path.back(), pattern[i % 3]));
  const auto fc = makePrefetchPredictor("forecache");
  ForeCacheModel model;
  std::vector<Camera> h;
  double err = 0, gap = 0;
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const Pose got = predictNextPose(*fc, h, path[i]);
    model.observe(poseFromPosition(Camera::fromPose(path[i], 8, 8).eye));
    gap = std::max(gap, poseDistance(got, i ? model.predictNext() : path[0]));
    if (i >= 30) err += poseDistance(got, path[i + 1]);
  }
  EXPECT_LT(gap, 1e-12);
  EXPECT_LT(err / 14, 1e-6);
  EXPECT_EQ(static_cast<const ForeCachePredictor&>(*fc).phase(), model.phase());
  // A new trajectory: the chain starts over, so two poses in it predict a repeat of its one move
  // (without the reset, the learnt pattern would predict another move).
  std::vector<Camera> fresh = camerasOf({Pose{1.1, 100, 200}, Pose{1.1, 103, 200}});
  Camera next;
  ASSERT_TRUE(fc->predict(fresh, next));
  const Pose p = poseFromPosition(next.eye);
  EXPECT_NEAR(p.distance, 1.1, 1e-9);
  EXPECT_NEAR(p.thetaDeg, 106.0, 1e-6);
  EXPECT_NEAR(p.phiDeg, 200.0, 1e-6);
  std::vector<int64_t> entries;
  EXPECT_FALSE(fc->predictEntries(fresh, entries));  // no file: no blocks
}
