// SPDX-License-Identifier: BSD-3-Clause
// What the GPU decoder's test and benchmark share: every entry's stored payload read from a file
// into one host buffer (4-byte aligned, as in the file), the GPU jobs of the decodable ones, and
// device buffers that free themselves.
#pragma once

#include <cuda_runtime_api.h>
#include <unistd.h>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "afam/cuda/decode/gpu_block_decoder.hpp"
#include "afam/format/afam_file.hpp"

namespace afam::gputest {

/// Every entry's stored bytes, at offset[i] of bytes (empty entries hold none).
struct StoredPayloads {
  std::vector<uint8_t> bytes;
  std::vector<uint64_t> offset;
  const uint8_t* of(size_t entry) const { return bytes.data() + offset[entry]; }
};

inline StoredPayloads readStoredPayloads(const AfamFile& file) {
  StoredPayloads s;
  uint64_t total = 0;
  for (const ModelEntry& e : file.entries()) {
    s.offset.push_back(total);
    total += (e.storedSize + 3) / 4 * 4;
  }
  s.bytes.assign(total + 4, 0);
  for (size_t i = 0; i < file.entries().size(); ++i) {
    const ModelEntry& e = file.entries()[i];
    uint64_t got = 0;
    while (got < e.storedSize) {
      const ssize_t n = ::pread(file.nativeHandle(), s.bytes.data() + s.offset[i] + got,
                                e.storedSize - got, off_t(e.offset + got));
      if (n <= 0) throw std::runtime_error(file.path() + ": cannot read a stored payload");
      got += uint64_t(n);
    }
  }
  return s;
}

/// The decodable entries of a file as one batch: jobs[k] decodes entries[k] into the output at
/// jobs[k].outputOffset; outputFloats in all.
struct DecodeBatch {
  std::vector<GpuDecodeJob> jobs;
  std::vector<size_t> entries;
  uint64_t outputFloats = 0;
  uint64_t storedBytes = 0;
  size_t coded = 0;  ///< of them coded (lanes frames)
};

inline DecodeBatch decodableBatch(const AfamFile& file, const StoredPayloads& stored) {
  DecodeBatch b;
  for (size_t i = 0; i < file.entries().size(); ++i) {
    const ModelEntry& e = file.entries()[i];
    if (!gpuDecodable(e, stored.of(i))) continue;
    b.jobs.push_back(gpuDecodeJob(e, stored.of(i), stored.offset[i], b.outputFloats));
    b.entries.push_back(i);
    b.outputFloats += uint64_t(controlCount(e));
    b.storedBytes += e.storedSize;
    b.coded += e.coded && e.kind != BlockKind::Constant;
  }
  return b;
}

/// Device memory of `bytes` bytes, freed when it goes.
class DeviceBuffer {
 public:
  explicit DeviceBuffer(size_t bytes) : bytes_(bytes) {
    if (cudaMalloc(&data_, bytes ? bytes : 1) != cudaSuccess)
      throw std::runtime_error("cudaMalloc of " + std::to_string(bytes) + " bytes failed");
  }
  ~DeviceBuffer() { (void)cudaFree(data_); }
  DeviceBuffer(const DeviceBuffer&) = delete;
  DeviceBuffer& operator=(const DeviceBuffer&) = delete;
  void upload(const void* host, size_t bytes) {
    if (cudaMemcpy(data_, host, bytes, cudaMemcpyHostToDevice) != cudaSuccess)
      throw std::runtime_error("upload failed");
  }
  void download(void* host, size_t bytes) const {
    if (cudaMemcpy(host, data_, bytes, cudaMemcpyDeviceToHost) != cudaSuccess)
      throw std::runtime_error("download failed");
  }
  void fill(int byte) {
    if (cudaMemset(data_, byte, bytes_) != cudaSuccess) throw std::runtime_error("memset failed");
  }
  void* data() const { return data_; }
  float* floats() const { return static_cast<float*>(data_); }

 private:
  void* data_ = nullptr;
  size_t bytes_ = 0;
};

}  // namespace afam::gputest
