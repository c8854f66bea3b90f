// SPDX-License-Identifier: BSD-3-Clause
// Format version 3's commit slots and step table: a reader takes the newest intact slot, so that
// a writer killed while writing a slot, or before it, leaves the previous commit in force; a
// damaged or inconsistent step table is refused naming the step.
#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/format/run_layout.hpp"

using namespace afam;

namespace {

CommitRecord record(uint64_t generation, uint64_t steps) {
  CommitRecord r;
  r.generation = generation;
  r.stepCount = steps;
  r.stepTableOffset = 4096 + 8 * generation;
  r.committedSize = r.stepTableOffset + stepTableBytes(steps);
  r.totalPayloadBytes = 1000 * steps;
  return r;
}

std::string messageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const FormatError& e) {
    return e.what();
  }
  return "";
}

std::vector<StepRow> threeSteps() {
  std::vector<StepRow> rows(3);
  for (int i = 0; i < 3; ++i) {
    rows[size_t(i)].time = 0.5 * i;
    rows[size_t(i)].indexOffset = kRunStepsOffset + 800 * uint64_t(i + 1);
    rows[size_t(i)].indexChecksum = 0x1234u + uint32_t(i);
    rows[size_t(i)].keyStep = i != 1;
    rows[size_t(i)].valueMin = -float(i);
    rows[size_t(i)].valueMax = float(10 + i);
  }
  return rows;
}

}  // namespace

TEST(RunLayout, TheNewestIntactSlotIsTakenAndTheOtherIsWrittenNext) {
  const auto a = encodeCommitSlot(record(4, 7)), b = encodeCommitSlot(record(5, 8));
  CommitChoice c = chooseCommit(a.data(), b.data(), "f");
  EXPECT_EQ(c.record, record(5, 8));
  EXPECT_EQ(c.slot, 1);
  EXPECT_EQ(c.nextSlot, 0);
  c = chooseCommit(b.data(), a.data(), "f");
  EXPECT_EQ(c.slot, 0);
  EXPECT_EQ(c.record.stepCount, 8u);
  // A slot torn while being written (any byte of it changed): the other one stays in force.
  for (size_t at = 0; at < kCommitSlotBytes; ++at) {
    auto torn = b;
    torn[at] = uint8_t(torn[at] ^ 0x5a);
    c = chooseCommit(a.data(), torn.data(), "f");
    ASSERT_EQ(c.record, record(4, 7)) << "byte " << at;
    EXPECT_EQ(c.nextSlot, 1) << "the damaged slot is the one the next append writes";
  }
  // A file committed once: slot B never written (zeros, generation 0).
  const std::array<uint8_t, kCommitSlotBytes> never{};
  c = chooseCommit(a.data(), never.data(), "f");
  EXPECT_EQ(c.slot, 0);
  EXPECT_EQ(c.nextSlot, 1);
}

TEST(RunLayout, NoIntactSlotOrTwoOfOneGenerationAreRefused) {
  const std::array<uint8_t, kCommitSlotBytes> never{};
  auto damaged = encodeCommitSlot(record(2, 3));
  damaged[9] ^= 1;
  EXPECT_NE(messageOf([&] {
              chooseCommit(never.data(), damaged.data(), "run.afam");
            }).find("run.afam: no committed step"),
            std::string::npos);
  const auto a = encodeCommitSlot(record(3, 3)), b = encodeCommitSlot(record(3, 4));
  EXPECT_NE(messageOf([&] {
              chooseCommit(a.data(), b.data(), "run.afam");
            }).find("both commit slots claim generation 3"),
            std::string::npos);
}

TEST(RunLayout, StepTableRoundTripsAndDamageIsRefusedNamingTheStep) {
  const std::vector<StepRow> rows = threeSteps();
  const uint64_t table = kRunStepsOffset + 800 * 4, index = 400;
  std::vector<uint8_t> b = encodeStepTable(rows);
  ASSERT_EQ(b.size(), stepTableBytes(3));
  const std::vector<StepRow> back = decodeStepTable(b.data(), 3, table, index, "r");
  ASSERT_EQ(back.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(back[i].time, rows[i].time);
    EXPECT_EQ(back[i].indexOffset, rows[i].indexOffset);
    EXPECT_EQ(back[i].indexChecksum, rows[i].indexChecksum);
    EXPECT_EQ(back[i].keyStep, rows[i].keyStep);
    EXPECT_EQ(back[i].valueMin, rows[i].valueMin);
    EXPECT_EQ(back[i].valueMax, rows[i].valueMax);
  }
  for (size_t at = 0; at < b.size(); ++at) {  // any damaged byte
    std::vector<uint8_t> d = b;
    d[at] = uint8_t(d[at] ^ 0x10);
    EXPECT_NE(messageOf([&] { decodeStepTable(d.data(), 3, table, index, "r"); }), "") << at;
  }
  auto refused = [&](std::vector<StepRow> r, const std::string& what, uint64_t idx = 400) {
    const std::vector<uint8_t> t = encodeStepTable(r);
    const std::string m = messageOf([&] { decodeStepTable(t.data(), r.size(), table, idx, "r"); });
    EXPECT_NE(m.find(what), std::string::npos) << "'" << m << "' lacks '" << what << "'";
  };
  std::vector<StepRow> r = rows;
  r[2].time = r[1].time;
  refused(r, "step 2: time 0.500000 does not follow 0.500000");
  r = rows;
  r[1].time = std::numeric_limits<double>::quiet_NaN();
  refused(r, "step 1: time is not finite");
  r = rows;
  r[0].keyStep = false;
  refused(r, "step 0: the first step is not a key step");
  r = rows;
  r[1].indexOffset += 4;
  refused(r, "step 1: index offset");
  refused(rows, "step 2: index offset", 900);  // step 2's index would run into the table
  r = rows;
  r[0].indexOffset = 8;
  refused(r, "step 0: index offset 8");
}
