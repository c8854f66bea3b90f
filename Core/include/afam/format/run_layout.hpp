// SPDX-License-Identifier: BSD-3-Clause
// The parts of format version 3 (a run of time steps in one file; docs/FORMAT.md, "Version 3")
// that make appending atomic: the two commit slots, of which a reader takes the newest intact
// one, and the step table they point to. Pure functions over bytes, so that the writer, the
// reader and the tests agree on one definition.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace afam {

/// Bytes of one commit slot, where the two slots start, and the first byte after them.
constexpr size_t kCommitSlotBytes = 64;
constexpr uint64_t kCommitSlotsOffset = 1024;
constexpr uint64_t kRunStepsOffset = kCommitSlotsOffset + 2 * kCommitSlotBytes;

/// What a commit slot says (docs/FORMAT.md, "Commit slots").
struct CommitRecord {
  uint64_t generation = 0;  ///< 1 for the first commit, one more at each append; 0 = never written
  uint64_t stepCount = 0;
  uint64_t stepTableOffset = 0;
  uint64_t committedSize = 0;  ///< the file's bytes up to the end of the step table's CRC
  uint64_t totalPayloadBytes = 0;
  bool operator==(const CommitRecord& o) const {
    return generation == o.generation && stepCount == o.stepCount &&
           stepTableOffset == o.stepTableOffset && committedSize == o.committedSize &&
           totalPayloadBytes == o.totalPayloadBytes;
  }
};

/// The 64 bytes of a slot holding `r` (its CRC-32 in the last four).
std::array<uint8_t, kCommitSlotBytes> encodeCommitSlot(const CommitRecord& r);

/// Which slot a reader takes, and which one the next append overwrites.
struct CommitChoice {
  CommitRecord record;
  int slot = 0;      ///< 0 (A) or 1 (B): the slot the record came from
  int nextSlot = 1;  ///< the other one: older, never written, or damaged
};

/// Of slots A and B (kCommitSlotBytes each), the intact one (CRC holds, generation not 0) with the
/// larger generation. Throws FormatError naming `path` when neither is intact ("no committed
/// step"), and when the two are intact with the same generation (only a damaged writer does that).
CommitChoice chooseCommit(const uint8_t* slotA, const uint8_t* slotB, const std::string& path);

/// One row of the step table (docs/FORMAT.md, "Step table").
struct StepRow {
  double time = 0;
  uint64_t indexOffset = 0;
  uint32_t indexChecksum = 0;
  bool keyStep = false;
  float valueMin = 0, valueMax = 0;
};

/// Bytes of the step table of `rows`: 32 a row, then the CRC-32 of the rows.
std::vector<uint8_t> encodeStepTable(const std::vector<StepRow>& rows);

/// Bytes a step table of `steps` rows takes.
constexpr uint64_t stepTableBytes(uint64_t steps) { return steps * 32 + 4; }

/// The rows of a step table (stepTableBytes(steps) bytes). Throws FormatError naming `path` and
/// the row when the CRC fails, times do not increase strictly or are not finite, an index offset
/// is not a multiple of 8 or does not leave room for `indexBytes` before `tableOffset`, an index
/// starts before the steps' area, step 0 is not a key step, or a flag bit is unknown.
std::vector<StepRow> decodeStepTable(const uint8_t* bytes, uint64_t steps, uint64_t tableOffset,
                                     uint64_t indexBytes, const std::string& path);

}  // namespace afam
