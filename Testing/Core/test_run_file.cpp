// SPDX-License-Identifier: BSD-3-Clause
// Format version 3 written by RunWriter and read by AfamFile::open(path, step): every step's
// models, references resolved to the payload that holds them within the key interval, each
// step's own ranges and errors; bad sequences refused by the writer, damage and truncation by
// the reader, bytes of an append that did not commit ignored.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/encode/model_sink.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/format/block_codec.hpp"
#include "afam/format/run_writer.hpp"
#include "afam/spline/fit.hpp"

#include "file_bytes.hpp"
#include "scratch_dir.hpp"

using namespace afam;
using afam_test::readAll;
using afam_test::writeAll;

namespace {

std::string scratch(const std::string& name) {
  return afam_test::scratchPath("afam_run_" + name);  // removed with its folder at exit
}

VolumeHeader gridHeader() {
  VolumeHeader h;
  h.dims = {17, 13, 9};
  h.levels = 2;
  h.blocksPerAxis = 2;
  h.degree = 2;
  h.errorBound = 0.01;
  h.relativeBound = true;
  h.valueMin = 0;
  h.valueMax = 100;
  h.sampling = LevelSampling::Box;
  return h;
}

/// A constant model of value v for the block (the smallest valid model of any block).
ModelEntry constantModel(const Partition& p, int degree, int level, Int3 ijk, float v) {
  ModelEntry m;
  m.level = level;
  m.block = ijk;
  m.samples = p.extent(level, ijk).samples;
  m.kind = BlockKind::Constant;
  for (int a = 0; a < 3; ++a) {
    m.degree[a] = effectiveDegree(degree, m.samples[a]);
    m.ncp[a] = m.degree[a] + 1;
  }
  m.storedSize = 4;
  m.minValue = m.maxValue = v;
  m.rmse = 0.001f * v;
  return m;
}

/// Every block of step `s`: stored with value 10 s + linear index, or a reference when
/// refer(level, linear) says so and the writer allows it.
template <typename Refer>
void writeStep(RunWriter& w, const VolumeHeader& h, int s, Refer&& refer) {
  w.beginStep(0.25 * s);
  const Partition& p = w.partition();
  for (int level = 0; level < h.levels; ++level)
    for (int64_t i = 0; i < p.blockCount(level); ++i) {
      const Int3 ijk = p.blockFromLinear(level, i);
      ModelEntry m = constantModel(p, h.degree, level, ijk, float(10 * s + i));
      if (refer(level, i)) {
        ASSERT_TRUE(w.canReference(level, ijk));
        w.addReference(m);
      } else {
        w.addStored(m, &m.minValue);
      }
    }
  w.endStep(float(10 * s), float(10 * s + 9));
}

std::string openError(const std::string& path, int64_t step) {
  try {
    AfamFile::open(path, step);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

/// A three-step run with key interval 3: step 1 refers to step 0 for its odd blocks, step 2 to
/// step 1 for blocks 1 and 2 (block 1 then two steps back).
std::string threeStepRun(const std::string& name) {
  const VolumeHeader h = gridHeader();
  const std::string path = scratch(name);
  RunWriter w(path, h, 3, 1.0);
  writeStep(w, h, 0, [](int, int64_t) { return false; });
  writeStep(w, h, 1, [](int level, int64_t i) { return level == 1 && i % 2 == 1; });
  writeStep(w, h, 2, [](int level, int64_t i) { return level == 1 && (i == 1 || i == 2); });
  w.commit();
  return path;
}

}  // namespace

TEST(RunFile, EveryStepReadsItsModelsWithReferencesResolved) {
  const std::string path = threeStepRun("three.afam");
  for (int64_t s = 0; s < 3; ++s) {
    SCOPED_TRACE("step " + std::to_string(s));
    auto f = AfamFile::open(path, s);
    EXPECT_EQ(f->version(), 3u);
    EXPECT_EQ(f->stepCount(), 3);
    EXPECT_EQ(f->step(), s);
    EXPECT_EQ(f->stepTimes(), (std::vector<double>{0.0, 0.25, 0.5}));
    EXPECT_EQ(f->keyInterval(), 3);
    const int64_t first = f->levelStart(1);
    for (int64_t i = first; i < int64_t(f->entries().size()); ++i) {
      const ModelEntry& e = f->entries()[size_t(i)];
      const int64_t li = i - first;
      // The step whose payload the block's model is.
      int64_t owner = s;
      if (s == 1 && li % 2 == 1) owner = 0;
      if (s == 2 && li == 1) owner = 0;
      if (s == 2 && li == 2) owner = 1;
      EXPECT_EQ(e.reference, owner != s) << i;
      EXPECT_EQ(e.ownerStep, owner) << i;
      EXPECT_EQ(f->readPayload(i)[0], float(10 * owner + li)) << i;
      EXPECT_EQ(e.minValue, float(10 * s + li)) << "the step's own range, block " << i;
    }
  }
  EXPECT_NE(openError(path, 3).find("step 3 of a run of 3 steps"), std::string::npos);
  std::remove(path.c_str());
}

/// The writer keeps each model it decodes for the next steps (RunWriter::kDecodedModelBytes): a
/// block that refers back keeps its owner's model, one stored anew gives its new model, never the
/// one kept for it before. Each block is asked twice per step (the second answer from the kept
/// model).
TEST(RunFile, ThePreviousModelFollowsEachStepsPayloadWhileKeptDecoded) {
  const VolumeHeader h = gridHeader();
  const std::string path = scratch("previous.afam");
  RunWriter w(path, h, 3, 1.0);
  const Partition& p = w.partition();
  const auto expectPrevious = [&](auto&& owner) {
    for (int64_t i = 0; i < p.blockCount(1); ++i)
      for (int ask = 0; ask < 2; ++ask) {
        ModelEntry e;
        std::vector<float> control;
        ASSERT_TRUE(w.previousModel(1, p.blockFromLinear(1, i), e, control));
        ASSERT_FALSE(control.empty());
        const int s = owner(i);
        EXPECT_EQ(control[0], float(10 * s + i)) << "block " << i << ", ask " << ask;
        EXPECT_EQ(e.ownerStep, s) << "block " << i;
      }
  };
  writeStep(w, h, 0, [](int, int64_t) { return false; });
  expectPrevious([](int64_t) { return 0; });
  writeStep(w, h, 1, [](int level, int64_t i) { return level == 1 && i % 2 == 1; });
  expectPrevious([](int64_t i) { return i % 2 == 1 ? 0 : 1; });
  writeStep(w, h, 2, [](int level, int64_t i) { return level == 1 && (i == 1 || i == 2); });
  expectPrevious([](int64_t i) { return i == 1 ? 0 : i == 2 ? 1 : 2; });
  std::remove(path.c_str());
}

/// A block coded in residuals step after step: the writer's model of the step before (decoded
/// from the model it kept and the newest residual) is, float for float, what a reader decodes
/// from the whole chain.
TEST(RunFile, APreviousModelOfResidualsIsTheReadersChain) {
  const VolumeHeader h = gridHeader();
  const std::string path = scratch("residuals.afam");
  RunWriter w(path, h, 8, 1.0);
  const Partition& p = w.partition();
  const Int3 b{0, 0, 0};
  const int64_t slot = p.blockCount(0);  // block 0 of level 1
  ModelEntry samples;
  samples.level = 1;
  samples.block = b;
  samples.samples = samples.ncp = p.extent(1, b).samples;
  samples.kind = BlockKind::Samples;
  samples.degree = {1, 1, 1};
  samples.coded = true;
  const size_t count = size_t(samples.ncp[0]) * size_t(samples.ncp[1]) * size_t(samples.ncp[2]);
  std::vector<std::vector<float>> asked;  // previousModel after each step
  constexpr int kSteps = 5;
  for (int s = 0; s < kSteps; ++s) {
    w.beginStep(s);
    for (int level = 0; level < h.levels; ++level)
      for (int64_t i = 0; i < p.blockCount(level); ++i) {
        const Int3 ijk = p.blockFromLinear(level, i);
        if (level == 1 && i == 0) continue;
        ModelEntry m = constantModel(p, h.degree, level, ijk, float(i));
        if (s > 0) {
          w.addReference(m);
        } else {
          w.addStored(m, &m.minValue);
        }
      }
    std::vector<float> values(count), reconstructed;
    for (size_t i = 0; i < count; ++i)  // step 0 the model, then small changes to it
      values[i] =
          s == 0 ? float(std::sin(0.37 * double(i))) : 0.01f * float(std::cos(double(i * s)));
    std::vector<uint8_t> bytes;
    ASSERT_TRUE(encodeValues(values.data(), samples.ncp, 1e-3, Predictor::IntegerLorenzo,
                             EntropyCoding{}, bytes, reconstructed));
    samples.storedSize = bytes.size();
    if (s == 0) {
      w.addStored(samples, bytes.data());
    } else {
      w.addResidual(samples, bytes.data());
    }
    w.endStep(0, 1);
    for (int ask = 0; ask < 2; ++ask) {  // the second from the model kept
      ModelEntry e;
      std::vector<float> control;
      ASSERT_TRUE(w.previousModel(1, b, e, control));
      if (ask == 0) asked.push_back(control);
      EXPECT_EQ(control, asked.back()) << "step " << s;
    }
  }
  w.commit();
  for (int s = 0; s < kSteps; ++s) {
    auto f = AfamFile::open(path, s);
    EXPECT_EQ(f->chain(slot).size(), s == 0 ? 0u : size_t(s + 1)) << "step " << s;
    EXPECT_EQ(f->readPayload(slot), asked[size_t(s)]) << "step " << s;
  }
  std::remove(path.c_str());
}

TEST(RunFile, TheWriterRefusesBadSequencesAndLongChains) {
  const VolumeHeader h = gridHeader();
  const std::string path = scratch("bad.afam");
  {
    RunWriter w(path, h, 2, 1.0);
    const Partition& p = w.partition();
    EXPECT_FALSE(w.canReference(0, {0, 0, 0})) << "nothing before the first step";
    writeStep(w, h, 0, [](int, int64_t) { return false; });
    EXPECT_THROW(w.beginStep(0.0), InvalidArgument) << "time does not increase";
    writeStep(w, h, 1, [](int level, int64_t) { return level == 0; });
    w.beginStep(1.0);
    EXPECT_FALSE(w.canReference(0, {0, 0, 0})) << "key interval 2: one reference at most";
    ModelEntry m = constantModel(p, h.degree, 0, {0, 0, 0}, 1.0f);
    EXPECT_THROW(w.addReference(m), InvalidArgument);
    try {
      w.endStep(0, 1);
      ADD_FAILURE() << "a step without its blocks ended";
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find("step 2 without level 0 block (0, 0, 0)"),
                std::string::npos)
          << e.what();
    }
    EXPECT_THROW(w.commit(), InvalidArgument) << "inside a step";
  }
  EXPECT_NE(openError(path, 0).find("cannot open"), std::string::npos)
      << "a writer destroyed before commit leaves nothing";
}

TEST(RunFile, UncommittedBytesAreIgnoredAndDamageIsRefused) {
  const std::string path = threeStepRun("damage.afam");
  const std::vector<char> good = readAll(path);
  std::vector<char> b = good;
  b.insert(b.end(), 4096, 'x');  // an append that was killed before its commit slot
  writeAll(path, b);
  EXPECT_EQ(AfamFile::open(path, 2)->stepCount(), 3);
  b.assign(good.begin(), good.end() - 1);
  writeAll(path, b);
  EXPECT_NE(openError(path, 0).find("truncated"), std::string::npos) << openError(path, 0);
  // Step 1's index damaged: step 1, and step 2 whose references walk through it, are refused;
  // step 0 is not. Where the index lies: commit slot A's step table, row 1.
  uint64_t table, index1;
  std::memcpy(&table, good.data() + 1024 + 16, 8);
  std::memcpy(&index1, good.data() + table + 32 + 8, 8);
  b = good;
  b[index1 + 20] = char(b[index1 + 20] ^ 0x08);
  writeAll(path, b);
  EXPECT_NE(openError(path, 1).find("index of step 1 checksum mismatch"), std::string::npos)
      << openError(path, 1);
  EXPECT_NE(openError(path, 2).find("index of step 1 checksum mismatch"), std::string::npos);
  EXPECT_EQ(openError(path, 0), "");
  b = good;
  b[1024 + 5] = char(b[1024 + 5] ^ 0x01);
  writeAll(path, b);
  EXPECT_NE(openError(path, 0).find("no committed step"), std::string::npos) << openError(path, 0);
  b = good;
  b[table + 3] = char(b[table + 3] ^ 0x40);
  writeAll(path, b);
  EXPECT_NE(openError(path, 0).find("step table checksum mismatch"), std::string::npos);
  std::remove(path.c_str());
}

TEST(RunFile, AppendedStepsCountOnceCommittedAndAnUnfinishedAppendIsCutOff) {
  const VolumeHeader h = gridHeader();
  const std::string path = threeStepRun("append.afam");
  const std::vector<char> before = readAll(path);
  {  // an append that does not commit (an exception, a kill): the file keeps its three steps
    std::unique_ptr<RunWriter> w = RunWriter::append(path);
    EXPECT_EQ(w->stepsDone(), 3);
    writeStep(*w, h, 3, [](int level, int64_t i) { return level == 1 && i == 0; });
    EXPECT_THROW(RunWriter::append(path), IoError) << "one appender at a time";
    EXPECT_EQ(AfamFile::open(path)->stepCount(), 3);
  }
  EXPECT_EQ(readAll(path), before) << "what the unfinished append wrote was cut off";
  std::unique_ptr<RunWriter> w = RunWriter::append(path);
  EXPECT_THROW(w->beginStep(0.5), InvalidArgument) << "time 0.5 does not follow 0.5";
  // Step 3 refers to step 2 for blocks 0 and 3 of level 1. Block 1 of step 2 is already two
  // references from its payload: the key interval 3 lets it refer no further; block 2, one.
  EXPECT_FALSE(w->canReference(1, w->partition().blockFromLinear(1, 1)));
  EXPECT_TRUE(w->canReference(1, w->partition().blockFromLinear(1, 2)));
  writeStep(*w, h, 3, [](int level, int64_t i) { return level == 1 && (i == 0 || i == 3); });
  w->commit();
  auto f = AfamFile::open(path, 3);
  EXPECT_EQ(f->stepCount(), 4);
  EXPECT_EQ(f->stepTimes().back(), 0.75);
  const int64_t first = f->levelStart(1);
  EXPECT_EQ(f->readPayload(first + 0)[0], 20.0f) << "block 0: step 2's payload";
  EXPECT_EQ(f->entries()[size_t(first)].ownerStep, 2);
  EXPECT_EQ(f->readPayload(first + 1)[0], 31.0f) << "block 1: stored again at step 3";
  EXPECT_EQ(AfamFile::open(path, 1)->readPayload(first + 1)[0], 0.0f + 1) << "steps before intact";
  uint64_t generationB;
  const std::vector<char> after = readAll(path);
  std::memcpy(&generationB, after.data() + 1024 + 64, 8);
  EXPECT_EQ(generationB, 2u) << "the append wrote the second commit slot";
  std::remove(path.c_str());
}

TEST(RunFile, AppendingToAFileOfOneStepIsRefused) {
  InMemoryModels mem;
  const VolumeHeader h = gridHeader();
  RunWriter probe(scratch("unused.afam"), h, 2, 1.0);  // only for the partition
  const Partition& p = probe.partition();
  mem.begin(h);
  for (int level = 0; level < h.levels; ++level)
    for (int64_t i = 0; i < p.blockCount(level); ++i) {
      const ModelEntry m = constantModel(p, h.degree, level, p.blockFromLinear(level, i), 1.0f);
      mem.add(m, &m.minValue);
    }
  const std::string path = scratch("one_step.afam");
  mem.write(path);
  try {
    RunWriter::append(path);
    ADD_FAILURE() << "appended to a file of one step";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("appending needs a run"), std::string::npos) << e.what();
  }
  std::remove(path.c_str());
}
