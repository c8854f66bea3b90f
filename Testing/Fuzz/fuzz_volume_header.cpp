// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: NRRD and MetaImage headers (volume_formats.hpp) and, when the samples are attached
// to the header, the source over them (raw or gzip/zlib inflated), read slab by slab. Input: one
// control byte (even: NRRD, odd: MetaImage), then the file. Detached data files are not opened: a
// fuzzed header may name any path (a FIFO would hang the run).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/volume/volume_formats.hpp"
#include "memory_file.hpp"

namespace {

constexpr int64_t kMaxVoxels = int64_t(1) << 16;  // what one run reads, at most

void readAllSlabs(afam::HeaderVolumeSource& source) {
  const afam::Index3 d = source.dims();
  const int64_t slab = std::max<int64_t>(1, std::min<int64_t>(d[2], 3));
  std::vector<float> out(static_cast<size_t>(d[0] * d[1] * slab));
  for (int64_t z = 0; z < d[2]; z += slab) source.readSlab(z, std::min(slab, d[2] - z), out.data());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static afam_fuzz::MemoryFile memory;
  const std::string& path = memory.write(data + 1, size - 1);
  afam::VolumeFileHeader header;
  try {
    header = (data[0] & 1) ? afam::readMetaImageHeader(path) : afam::readNrrdHeader(path);
  } catch (const afam::Error&) {
    return 0;
  }
  const afam::Index3 d = header.dims;
  if (d[0] < 1 || d[1] < 1 || d[2] < 1) __builtin_trap();  // a parsed header promises its dims
  if (header.dataPath != header.headerPath || d[0] > kMaxVoxels || d[1] > kMaxVoxels ||
      d[2] > kMaxVoxels || d[0] * d[1] * d[2] > kMaxVoxels)
    return 0;
  try {
    afam::HeaderVolumeSource source(header);
    readAllSlabs(source);
  } catch (const afam::Error&) {
  }
  return 0;
}
