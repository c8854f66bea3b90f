// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: the .afam reader. AfamFile::open (header, index), then readPayload of every entry
// and the decoding of each payload (and its compact form, which must expand to the same floats),
// then one level decoded as a whole; for a run of steps, the same again at its last step.
// Input: one control byte (which checksums to recompute after mutation, afam_checksums.hpp),
// then the file's bytes. Any exception of the afam error types is a clean refusal; anything else
// (a crash, a sanitizer report, another exception type) is a finding.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/encode/encoder.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/render/level_decode.hpp"
#include "afam_checksums.hpp"
#include "memory_file.hpp"

namespace {

// Decoding is skipped for blocks and levels larger than these (a valid file may hold big ones,
// and decoding them is slow under the fuzzer's instrumentation; the fuzzer looks for memory
// errors, not for how long a large decode takes).
constexpr int64_t kMaxDecodedSamples = int64_t(1) << 12;
constexpr int64_t kMaxDecodedLevelSamples = int64_t(1) << 15;

// Whether n0 * n1 * n2 <= limit, without overflowing on huge sizes.
template <typename Sizes>
bool atMost(const Sizes& n, int64_t limit) {
  int64_t product = 1;
  for (int a = 0; a < 3; ++a) {
    if (n[a] < 0 || n[a] > limit) return false;
    product *= n[a];
    if (product > limit) return false;
  }
  return true;
}

// The one place where a payload becomes samples: a new payload kind hooks its decoder in here.
void decodeEntry(const afam::AfamFile& file, int64_t i, std::vector<float>& samples) {
  const afam::ModelEntry& e = file.entries()[static_cast<size_t>(i)];
  const std::vector<float> payload = file.readPayload(i);
  if (!atMost(e.samples, kMaxDecodedSamples) || !atMost(e.ncp, kMaxDecodedSamples)) return;
  afam::decodeBlockSamples(e, payload.data(), file.header().mode, samples);
  // The compact form a cache keeps must read back as the same floats.
  std::vector<float> compact;
  const afam::CompactForm f = file.readCompact(i, 0.75, compact);
  if (f.width == 0) return;
  std::vector<float> expanded(payload.size());
  afam::expandCompact(compact.data(), f, expanded.size(), expanded.data());
  if (std::memcmp(expanded.data(), payload.data(), payload.size() * sizeof(float)) != 0)
    __builtin_trap();
}

void decodeCoarsestLevel(const afam::AfamFile& file) {
  const afam::LevelGrid grid = afam::levelGrid(file.partition(), 0);
  if (!atMost(grid.dims, kMaxDecodedLevelSamples)) return;
  std::vector<float> out(static_cast<size_t>(grid.dims[0] * grid.dims[1] * grid.dims[2]));
  afam::decodeLevelBox(file, 0, {0, 0, 0}, {grid.dims[0] - 1, grid.dims[1] - 1, grid.dims[2] - 1},
                       out.data());
}

/// Every entry read and decoded, then (when all were) the coarsest level as a whole.
void readAll(const afam::AfamFile& file) {
  std::vector<float> samples;
  bool allRead = true;
  for (int64_t i = 0; i < static_cast<int64_t>(file.entries().size()); ++i) {
    try {
      decodeEntry(file, i, samples);
    } catch (const afam::Error&) {
      allRead = false;
    }
  }
  if (allRead) {
    try {
      decodeCoarsestLevel(file);
    } catch (const afam::Error&) {
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static afam_fuzz::MemoryFile memory;
  std::vector<uint8_t> bytes(data + 1, data + size);
  afam_fuzz::fixAfamChecksums(bytes, data[0]);
  const std::string& path = memory.write(bytes.data(), bytes.size());
  std::shared_ptr<const afam::AfamFile> file;
  try {
    file = afam::AfamFile::open(path);
  } catch (const afam::Error&) {
    return 0;
  }
  readAll(*file);
  if (file->stepCount() > 1) {  // a run: its last step too, references walked back
    try {
      readAll(*afam::AfamFile::open(path, file->stepCount() - 1));
    } catch (const afam::Error&) {
    }
  }
  return 0;
}
