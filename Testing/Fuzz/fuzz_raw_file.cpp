// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: raw volume files. The name convention (name_XxYxZ_type.raw, parseRawName) and the
// type names (parseSampleType), then RawFileSource over the bytes with the parsed dims and type,
// read slab by slab. Input: the file name, a NUL byte, the file's contents.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/encode/encoder.hpp"
#include "memory_file.hpp"

namespace {

constexpr int64_t kMaxVoxels = int64_t(1) << 16;  // what one run reads, at most

void readAllSlabs(const std::string& path, const afam::Index3& dims, afam::SampleType type) {
  afam::RawFileSource source(path, dims, type);
  const int64_t plane = dims[0] * dims[1];
  const int64_t slab = std::max<int64_t>(1, std::min<int64_t>(dims[2], 3));
  std::vector<float> out(static_cast<size_t>(plane * slab));
  for (int64_t z = 0; z < dims[2]; z += slab)
    source.readSlab(z, std::min(slab, dims[2] - z), out.data());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static afam_fuzz::MemoryFile memory;
  const auto* nul = static_cast<const uint8_t*>(std::memchr(data, 0, size));
  const size_t nameLength = nul ? static_cast<size_t>(nul - data) : size;
  const std::string name(reinterpret_cast<const char*>(data), nameLength);
  try {
    (void)afam::parseSampleType(name);
  } catch (const afam::Error&) {
  }
  afam::Index3 dims{};
  afam::SampleType type{};
  if (!afam::parseRawName(name, dims, type)) return 0;
  if (dims[0] < 1 || dims[1] < 1 || dims[2] < 1) __builtin_trap();  // parseRawName promised dims
  if (dims[0] > kMaxVoxels || dims[1] > kMaxVoxels || dims[2] > kMaxVoxels ||
      dims[0] * dims[1] * dims[2] > kMaxVoxels)
    return 0;
  const size_t contentStart = nul ? nameLength + 1 : size;
  const std::string& path = memory.write(data + contentStart, size - contentStart);
  try {
    readAllSlabs(path, dims, type);
  } catch (const afam::Error&) {
  }
  return 0;
}
