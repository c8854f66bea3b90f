// SPDX-License-Identifier: BSD-3-Clause
// Residuals in time (format version 3, in-time coding 2): a block that changes a little from one
// step to the next is stored as a coded difference to the step before's decoded model. Every
// step meets the bound as a reader decodes it, no chain runs past the key interval, a damaged
// payload of a chain is named with its step, and an appended step continues the chains.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/encode/encode_run.hpp"
#include "afam/encode/first_step_blocks.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/render/level_decode.hpp"
#include "moving_blob.hpp"
#include "scratch_dir.hpp"

using namespace afam;

namespace {

std::string scratch(const std::string& name) {
  return afam_test::scratchPath("afam_residual_" + name);  // removed with its folder at exit
}

const Index3 kDims{36, 32, 28};

std::vector<float> drifting(int k) { return afam_test::driftingWaves(kDims, k); }

double decodedRmse(const AfamFile& f, const std::vector<float>& truth) {
  std::vector<float> out(truth.size());
  decodeLevelBox(f, f.header().levels - 1, {0, 0, 0}, {kDims[0] - 1, kDims[1] - 1, kDims[2] - 1},
                 out.data());
  double sum = 0;
  for (size_t i = 0; i < out.size(); ++i) sum += double(out[i] - truth[i]) * (out[i] - truth[i]);
  return std::sqrt(sum / double(out.size()));
}

/// `count` steps of the drifting field.
std::vector<std::vector<float>> drift(int count) {
  std::vector<std::vector<float>> out;
  for (int k = 0; k < count; ++k) out.push_back(drifting(k));
  return out;
}

/// Every coded block to the whole bound (no headroom), so that the chains these tests look at run
/// unbroken from step 0 (ARunLeavesHeadroom looks at the headroom).
EncoderOptions options() {
  EncoderOptions opt = afam_test::runTestOptions(3);
  opt.runCodedShare = 1.0;
  return opt;
}

}  // namespace

TEST(ResidualCoding, ADriftingRunIsCodedInResidualsWithinTheBoundAndTheKeyInterval) {
  afam_test::InMemoryRun series(kDims, drift(7));
  RunOptions run;
  run.keyInterval = 4;
  const std::string path = scratch("drifting.afam");
  const RunStats st = encodeRun(series.steps, options(), run, path);
  int64_t residuals = 0;
  for (size_t s = 1; s < st.residuals.size(); ++s) residuals += st.residuals[s];
  EXPECT_EQ(st.residuals[0], 0);
  EXPECT_EQ(st.residuals[4], 0) << "step 4 is a key step (K = 4)";
  EXPECT_GT(residuals, 20) << "most changed blocks are residuals";
  for (int64_t s = 0; s < 7; ++s) {
    SCOPED_TRACE("step " + std::to_string(s));
    auto f = AfamFile::open(path, s);
    int64_t found = 0;
    for (size_t i = 0; i < f->entries().size(); ++i) {
      const ModelEntry& e = f->entries()[i];
      const auto& chain = f->chain(int64_t(i));
      found += e.residual && !e.reference;
      EXPECT_LE(e.rmse, st.bound * (1 + 1e-6));
      EXPECT_LE(e.chainLength, uint32_t(run.keyInterval)) << "at most K payloads";
      if (e.residual) {
        ASSERT_EQ(chain.size(), e.chainLength);
        EXPECT_GE(chain.size(), 2u);
        EXPECT_EQ(chain.back().offset, e.offset) << "the newest payload last";
        EXPECT_LE(s - chain.front().step, run.keyInterval - 1);
        for (size_t k = 1; k < chain.size(); ++k) EXPECT_GT(chain[k].step, chain[k - 1].step);
      } else {
        EXPECT_TRUE(chain.empty());
      }
    }
    EXPECT_EQ(found, st.residuals[size_t(s)]);
    EXPECT_LE(decodedRmse(*f, series.data[size_t(s)]), st.bound);
  }
  // Against one file per step at the same bound in data units.
  EncoderOptions absolute = options();
  absolute.errorBound = st.bound;
  absolute.relativeBound = false;
  uint64_t separate = 0, inRun = 0;
  for (size_t k = 0; k < 7; ++k) {
    const std::string one = scratch("one.afam");
    separate += encodeVolume(series.sources[k], absolute, one).payloadBytes;
    inRun += st.steps[k].payloadBytes;
    std::remove(one.c_str());
  }
  EXPECT_LT(double(inRun), 0.7 * double(separate))
      << inRun << " payload bytes against " << separate << " in seven files";
  std::remove(path.c_str());
}

TEST(ResidualCoding, ADamagedPayloadOfAChainIsNamedWithItsStep) {
  afam_test::InMemoryRun series(kDims, drift(3));
  RunOptions run;
  run.keyInterval = 8;
  const std::string path = scratch("damaged.afam");
  encodeRun(series.steps, options(), run, path);
  auto f = AfamFile::open(path, 2);
  int64_t victim = -1;
  for (size_t i = 0; i < f->entries().size() && victim < 0; ++i)
    if (f->entries()[i].residual && f->chain(int64_t(i)).front().step == 0) victim = int64_t(i);
  ASSERT_GE(victim, 0) << "a block coded on step 0 through residuals";
  const PayloadPart base = f->chain(victim).front();
  f.reset();
  {
    std::fstream io(path, std::ios::in | std::ios::out | std::ios::binary);
    io.seekg(std::streamoff(base.offset + base.storedSize / 2));
    char c = 0;
    io.read(&c, 1);
    c = char(c ^ 0x5a);
    io.seekp(std::streamoff(base.offset + base.storedSize / 2));
    io.write(&c, 1);
  }
  auto damaged = AfamFile::open(path, 2);  // the indexes are intact
  std::vector<float> out(damaged->entries()[size_t(victim)].size / 4);
  try {
    damaged->readPayload(victim, out.data());
    FAIL() << "a damaged payload decoded";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("checksum mismatch"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("of step 0"), std::string::npos) << e.what();
  }
  std::remove(path.c_str());
}

TEST(ResidualCoding, AnAppendedStepContinuesTheChains) {
  afam_test::InMemoryRun series(kDims, drift(4));
  RunOptions run;
  run.keyInterval = 6;
  const std::string path = scratch("append.afam");
  const std::vector<VolumeSource*> first(series.steps.begin(), series.steps.begin() + 3);
  const RunStats st = encodeRun(first, options(), run, path);
  const RunStats added = appendStep(series.sources[3], 3.0, options(), path);
  EXPECT_GT(added.residuals[0], 0);
  auto f = AfamFile::open(path, 3);
  ASSERT_EQ(f->stepCount(), 4);
  uint32_t longest = 0;
  for (const ModelEntry& e : f->entries()) longest = std::max(longest, e.chainLength);
  EXPECT_EQ(longest, 4u) << "residuals at steps 1, 2 and 3 on step 0's payload";
  EXPECT_LE(decodedRmse(*f, series.data[3]), st.bound);
  std::remove(path.c_str());
}

TEST(ResidualCoding, ARunLeavesHeadroomForReferencesWhereItDriftsSlowly) {
  // A field drifting by about a tenth of the bound a step: coded to 0.7 of the bound where a block
  // moved little, the steps after refer to it; coded to the bound, every step needs a residual.
  std::vector<std::vector<float>> values;
  for (int k = 0; k < 8; ++k) values.push_back(afam_test::driftingWaves(kDims, k, 0.01));
  afam_test::InMemoryRun series(kDims, std::move(values));
  EncoderOptions tight = options(), headroom = options();
  headroom.runCodedShare = 0.7;
  const std::string a = scratch("to_the_bound.afam"), b = scratch("headroom.afam");
  const RunStats full = encodeRun(series.steps, tight, RunOptions{}, a);
  const RunStats room = encodeRun(series.steps, headroom, RunOptions{}, b);
  int64_t refsFull = 0, refsRoom = 0;
  for (size_t k = 0; k < 8; ++k) {
    refsFull += full.references[k];
    refsRoom += room.references[k];
  }
  EXPECT_GT(refsRoom, refsFull + 20) << "blocks kept as references";
  EXPECT_LT(room.bytesOut, full.bytesOut) << "a smaller run";
  for (int64_t s = 0; s < 8; ++s) {
    auto f = AfamFile::open(b, s);
    EXPECT_LE(decodedRmse(*f, series.data[size_t(s)]), room.bound) << "step " << s;
    for (const ModelEntry& e : f->entries()) EXPECT_LE(e.rmse, room.bound * (1 + 1e-6));
  }
  std::remove(a.c_str());
  std::remove(b.c_str());
}

TEST(ResidualCoding, TheFirstStepGetsHeadroomByTrialWhereTheStepsAfterBuildOnIt) {
  // Two runs of two steps: a blob moving by a quarter voxel (the second step builds on the first,
  // whose finer models leave its residuals more of the bound) and two unrelated fields (headroom
  // on the first step is only cost). RunEncoder, given one step at a time, codes the first step
  // to the bound, or with headroom on every block when told; encodeRun tries both on its first
  // steps and takes, block by block, the one that stored fewer bytes (on both runs fewer than
  // either: 5,780 B against 6,044 and 5,980 B on the blob when written).
  const std::vector<std::vector<float>> slow = {afam_test::movingBlob(kDims, 0, 0.25),
                                                afam_test::movingBlob(kDims, 1, 0.25)};
  std::vector<float> other = afam_test::movingBlob(kDims, 0);
  for (float& v : other) v = 2.f * v - 20.f;  // about the waves' range
  const std::vector<std::vector<float>> unrelated = {afam_test::driftingWaves(kDims, 0), other};
  for (const auto* steps : {&slow, &unrelated}) {
    const bool slowly = steps == &slow;
    SCOPED_TRACE(slowly ? "slowly drifting" : "unrelated steps");
    afam_test::InMemoryRun series(kDims, *steps);
    EncoderOptions opt = afam_test::runTestOptions(3);
    const std::string path = scratch("first_step.afam");
    const RunStats trial = encodeRun(series.steps, opt, RunOptions{}, path);
    auto stepped = [&](bool headroom) {
      EncoderOptions o = opt;
      if (headroom) o.firstStepHeadroom = [](int, Int3) { return true; };
      RunEncoder encoder(path, o, 16, trial.valueMin, trial.valueMax);
      for (size_t k = 0; k < steps->size(); ++k) encoder.addStep(*series.steps[k], double(k));
      return encoder.commit().bytesOut;
    };
    const uint64_t toTheBound = stepped(false), everywhere = stepped(true);
    EXPECT_LT(slowly ? everywhere : toTheBound, slowly ? toTheBound : everywhere)
        << "where headroom pays: to the bound " << toTheBound << " B, everywhere " << everywhere;
    EXPECT_LE(trial.bytesOut, std::min(toTheBound, everywhere))
        << "to the bound " << toTheBound << " B, everywhere " << everywhere << " B";
  }
}

TEST(ResidualCoding, TheRunTakesTheTrialsFirstStepBlocksAndWritesTheSameBytes) {
  // encodeRun's trial encodes the first step with and without headroom; the run then encodes it
  // with a mixture. A block is taken from the trial where its bound and search are the trial's
  // (here every block's: one trial or the other): the file is the one the run writes fitting
  // every block again.
  const std::vector<std::vector<float>> steps = {afam_test::movingBlob(kDims, 0, 0.25),
                                                 afam_test::movingBlob(kDims, 1, 0.25)};
  afam_test::InMemoryRun series(kDims, steps);
  EncoderOptions opt = afam_test::runTestOptions(4);  // 73 blocks, 8 fitted again
  opt.levels = 3;
  const auto mixture = [](int level, Int3 b) { return (level + b[0] + b[1] + b[2]) % 2 == 1; };
  const std::string path = scratch("taken.afam");
  const RunStats whole = encodeRun(series.steps, opt, RunOptions{}, path);
  auto blocks = std::make_shared<FirstStepBlocks>();
  const auto encode = [&](std::function<bool(int, Int3)> headroom, bool commit) {
    EncoderOptions o = opt;
    o.firstStepHeadroom = std::move(headroom);
    o.firstStepBlocks = blocks;
    RunEncoder encoder(path, o, 16, whole.valueMin, whole.valueMax);
    for (size_t k = 0; k < steps.size(); ++k) encoder.addStep(*series.steps[k], double(k));
    return commit ? encoder.commit() : encoder.stepStats();
  };
  const auto bytesOf = [&] {
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), {});
  };
  const RunStats fitted = encode(mixture, true);  // nothing kept yet: every block fitted
  const std::string expected = bytesOf();
  const int64_t firstBlocks = fitted.steps[0].blocks;
  ASSERT_EQ(blocks->kept(), firstBlocks) << "its first step kept while keeping";
  blocks = std::make_shared<FirstStepBlocks>();
  encode(nullptr, false);                         // the trial: to the bound
  encode([](int, Int3) { return true; }, false);  // and with headroom everywhere
  EXPECT_EQ(blocks->kept(), 2 * firstBlocks) << "each block in each trial";
  blocks->startTaking();
  const RunStats taken = encode(mixture, true);
  EXPECT_EQ(bytesOf(), expected) << "the same file, byte for byte";
  EXPECT_EQ(taken.bytesOut, fitted.bytesOut);
  EXPECT_EQ(blocks->taken(), firstBlocks) << "every block's bound is one trial's";
  EXPECT_LT(taken.steps[0].fits, fitted.steps[0].fits);
  EXPECT_GT(whole.firstStepTaken, 0) << "encodeRun takes the trial's blocks";
  std::remove(path.c_str());
}

TEST(ResidualCoding, AStepAtATimeEncodesTheRunEncodeRunWrites) {
  afam_test::InMemoryRun series(kDims, drift(3));
  const std::string whole = scratch("whole.afam"), stepped = scratch("stepped.afam");
  const RunStats st = encodeRun(series.steps, options(), RunOptions{}, whole);
  {
    RunEncoder encoder(stepped, options(), 16, st.valueMin, st.valueMax);
    for (size_t k = 0; k < 3; ++k) encoder.addStep(*series.steps[k], double(k));
    EXPECT_FALSE(std::ifstream(stepped).good()) << "nothing before the commit";
    EXPECT_EQ(encoder.commit().bytesOut, st.bytesOut);
  }
  std::ifstream a(whole, std::ios::binary), b(stepped, std::ios::binary);
  const std::string bytesA((std::istreambuf_iterator<char>(a)), {}),
      bytesB((std::istreambuf_iterator<char>(b)), {});
  EXPECT_EQ(bytesA, bytesB) << "the same file, byte for byte";
  // A step of another grid is named and the encoder left without a commit leaves nothing.
  const std::string refused = scratch("refused.afam");
  {
    RunEncoder encoder(refused, options(), 16, st.valueMin, st.valueMax);
    encoder.addStep(*series.steps[0], 0.0);
    const std::vector<float> other(size_t(kDims[0] * kDims[1] * (kDims[2] - 1)), 1.0f);
    ArraySource smaller(other.data(), {kDims[0], kDims[1], kDims[2] - 1});
    try {
      encoder.addStep(smaller, 1.0);
      FAIL() << "a step of another grid was encoded";
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find("step 1"), std::string::npos) << e.what();
    }
    EXPECT_THROW(encoder.addStep(*series.steps[1], 0.0), InvalidArgument) << "time goes back";
  }
  EXPECT_FALSE(std::ifstream(refused).good());
  std::remove(whole.c_str());
  std::remove(stepped.c_str());
}
