// SPDX-License-Identifier: BSD-3-Clause
#include "afam/format/run_layout.hpp"

#include <cmath>
#include <cstring>

#include "afam/base/errors.hpp"
#include "afam/format/afam_file.hpp"

namespace afam {

namespace {

template <typename T>
void put(uint8_t* at, T v) {
  std::memcpy(at, &v, sizeof v);
}

template <typename T>
T get(const uint8_t* at) {
  T v;
  std::memcpy(&v, at, sizeof v);
  return v;
}

constexpr size_t kRowBytes = 32;
constexpr uint32_t kKeyStepFlag = 1;

/// The slot's record when it is intact and was written, else false.
bool decodeSlot(const uint8_t* b, CommitRecord& r) {
  if (crc32(b, 60) != get<uint32_t>(b + 60)) return false;
  r.generation = get<uint64_t>(b);
  r.stepCount = get<uint64_t>(b + 8);
  r.stepTableOffset = get<uint64_t>(b + 16);
  r.committedSize = get<uint64_t>(b + 24);
  r.totalPayloadBytes = get<uint64_t>(b + 32);
  return r.generation != 0;
}

}  // namespace

std::array<uint8_t, kCommitSlotBytes> encodeCommitSlot(const CommitRecord& r) {
  std::array<uint8_t, kCommitSlotBytes> b{};
  put(b.data(), r.generation);
  put(b.data() + 8, r.stepCount);
  put(b.data() + 16, r.stepTableOffset);
  put(b.data() + 24, r.committedSize);
  put(b.data() + 32, r.totalPayloadBytes);
  put(b.data() + 60, crc32(b.data(), 60));
  return b;
}

CommitChoice chooseCommit(const uint8_t* slotA, const uint8_t* slotB, const std::string& path) {
  CommitRecord a, b;
  const bool hasA = decodeSlot(slotA, a), hasB = decodeSlot(slotB, b);
  if (!hasA && !hasB)
    throw FormatError(path + ": no committed step (both commit slots are empty or damaged)");
  if (hasA && hasB && a.generation == b.generation)
    throw FormatError(path + ": both commit slots claim generation " +
                      std::to_string(a.generation));
  CommitChoice c;
  const bool takeA = hasA && (!hasB || a.generation > b.generation);
  c.record = takeA ? a : b;
  c.slot = takeA ? 0 : 1;
  c.nextSlot = 1 - c.slot;
  return c;
}

std::vector<uint8_t> encodeStepTable(const std::vector<StepRow>& rows) {
  std::vector<uint8_t> b(stepTableBytes(rows.size()), 0);
  for (size_t i = 0; i < rows.size(); ++i) {
    uint8_t* at = b.data() + i * kRowBytes;
    put(at, rows[i].time);
    put(at + 8, rows[i].indexOffset);
    put(at + 16, rows[i].indexChecksum);
    put(at + 20, rows[i].keyStep ? kKeyStepFlag : 0u);
    put(at + 24, rows[i].valueMin);
    put(at + 28, rows[i].valueMax);
  }
  put(b.data() + rows.size() * kRowBytes, crc32(b.data(), rows.size() * kRowBytes));
  return b;
}

std::vector<StepRow> decodeStepTable(const uint8_t* bytes, uint64_t steps, uint64_t tableOffset,
                                     uint64_t indexBytes, const std::string& path) {
  const auto bad = [&](uint64_t row, const std::string& what) {
    return FormatError(path + ": step table, step " + std::to_string(row) + ": " + what);
  };
  if (steps == 0) throw FormatError(path + ": step table of no step");
  if (crc32(bytes, steps * kRowBytes) != get<uint32_t>(bytes + steps * kRowBytes))
    throw FormatError(path + ": step table checksum mismatch (step table damaged)");
  std::vector<StepRow> rows(steps);
  for (uint64_t i = 0; i < steps; ++i) {
    const uint8_t* at = bytes + i * kRowBytes;
    StepRow& r = rows[i];
    r.time = get<double>(at);
    r.indexOffset = get<uint64_t>(at + 8);
    r.indexChecksum = get<uint32_t>(at + 16);
    const uint32_t flags = get<uint32_t>(at + 20);
    r.keyStep = (flags & kKeyStepFlag) != 0;
    r.valueMin = get<float>(at + 24);
    r.valueMax = get<float>(at + 28);
    if (!std::isfinite(r.time)) throw bad(i, "time is not finite");
    if (i > 0 && !(r.time > rows[i - 1].time))
      throw bad(i, "time " + std::to_string(r.time) + " does not follow " +
                       std::to_string(rows[i - 1].time));
    if ((flags & ~kKeyStepFlag) != 0) throw bad(i, "unknown flags " + std::to_string(flags));
    if (i == 0 && !r.keyStep) throw bad(i, "the first step is not a key step");
    if (r.indexOffset % 8 != 0 || r.indexOffset < kRunStepsOffset || r.indexOffset > tableOffset ||
        tableOffset - r.indexOffset < indexBytes)
      throw bad(i, "index offset " + std::to_string(r.indexOffset) +
                       " is misaligned or leaves no room for its " + std::to_string(indexBytes) +
                       " bytes before the step table at " + std::to_string(tableOffset));
  }
  return rows;
}

}  // namespace afam
