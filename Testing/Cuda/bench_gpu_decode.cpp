// SPDX-License-Identifier: BSD-3-Clause
// Decoding speed of a file's payloads on the GPU (GpuBlockDecoder) and on one CPU thread
// (decodeStoredPayload), in one run, with the stored bytes already in memory on each side (the
// whole compressed file resident on the GPU):
//   bench_gpu_decode FILE.afam [--rounds N]
// Every decodable entry (gpuDecodable) is decoded N times on each side; the median time is
// reported as GB/s of decoded float32 control points, once for all of them and once for the coded
// ones alone (constants fill at memory speed and would flatter the total). The GPU's floats are
// compared with the CPU's (mismatches=0).
#include <cuda_runtime_api.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "afam/cuda/common/gpu_error.hpp"
#include "afam/cuda/decode/gpu_block_decoder.hpp"
#include "gpu_decode_batch.hpp"

namespace {

using namespace afam;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

/// The batch's jobs of coded payloads only, their outputs packed from 0.
gputest::DecodeBatch codedOnly(const gputest::DecodeBatch& all) {
  gputest::DecodeBatch b;
  for (size_t k = 0; k < all.jobs.size(); ++k) {
    if (all.jobs[k].kind != GpuDecodeKind::IntegerLorenzo) continue;
    GpuDecodeJob j = all.jobs[k];
    j.outputOffset = b.outputFloats;
    b.jobs.push_back(j);
    b.entries.push_back(all.entries[k]);
    b.outputFloats += uint64_t(j.ncp[0]) * uint64_t(j.ncp[1]) * uint64_t(j.ncp[2]);
    b.storedBytes += j.storedBytes;
    ++b.coded;
  }
  return b;
}

/// Median milliseconds of `rounds` GPU decodes of the batch (cudaEvents on the decoder's stream),
/// after one untimed; `failed` counts jobs whose status is not 0.
double timeGpu(GpuBlockDecoder& decoder, const gputest::DecodeBatch& b, const void* payloads,
               float* output, int rounds, size_t& failed) {
  cudaStream_t stream = static_cast<cudaStream_t>(decoder.stream());
  cudaEvent_t start, stop;
  cudaEventCreate(&start);
  cudaEventCreate(&stop);
  const std::vector<uint32_t>& status = decoder.decode(b.jobs, payloads, output);
  failed = size_t(std::count_if(status.begin(), status.end(), [](uint32_t s) { return s != 0; }));
  std::vector<double> ms;
  for (int r = 0; r < rounds; ++r) {
    cudaEventRecord(start, stream);
    decoder.decodeAsync(b.jobs, payloads, output);
    cudaEventRecord(stop, stream);
    decoder.wait();
    float t = 0;
    cudaEventElapsedTime(&t, start, stop);
    ms.push_back(double(t));
  }
  cudaEventDestroy(start);
  cudaEventDestroy(stop);
  return median(ms);
}

/// Median milliseconds of `rounds` decodes of the batch's entries on this thread into out.
double timeCpu(const AfamFile& file, const gputest::StoredPayloads& stored,
               const gputest::DecodeBatch& b, int rounds, std::vector<float>& out) {
  out.assign(b.outputFloats, 0.0f);
  std::vector<double> ms;
  for (int r = 0; r < rounds; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    for (size_t k = 0; k < b.jobs.size(); ++k) {
      const size_t i = b.entries[k];
      decodeStoredPayload(file.entries()[i], stored.of(i), out.data() + b.jobs[k].outputOffset,
                          file.path());
    }
    ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  return median(ms);
}

size_t mismatches(const gputest::DecodeBatch& b, const std::vector<float>& cpu,
                  const std::vector<float>& gpu) {
  size_t m = 0;
  for (const GpuDecodeJob& j : b.jobs) {
    const size_t n = size_t(j.ncp[0]) * size_t(j.ncp[1]) * size_t(j.ncp[2]);
    m += std::memcmp(cpu.data() + j.outputOffset, gpu.data() + j.outputOffset, n * 4) != 0;
  }
  return m;
}

/// Times and checks one batch; prints its gpu_decode and cpu_decode lines.
void run(const AfamFile& file, const gputest::StoredPayloads& stored, const gputest::DecodeBatch& b,
         const char* label, int rounds, const gputest::DeviceBuffer& payloads) {
  gputest::DeviceBuffer output(b.outputFloats * 4);
  GpuBlockDecoder decoder;
  size_t failed = 0;
  const double gpuMs = timeGpu(decoder, b, payloads.data(), output.floats(), rounds, failed);
  std::vector<float> gpu(b.outputFloats), cpu;
  output.download(gpu.data(), gpu.size() * 4);
  const double cpuMs = timeCpu(file, stored, b, rounds, cpu);
  const double decoded = double(b.outputFloats) * 4;
  std::printf(
      "gpu_decode%s entries=%zu decodable=%zu coded=%zu stored_bytes=%llu decoded_bytes=%.0f "
      "median_ms=%.3f gbps=%.1f failed=%zu mismatches=%zu\n",
      label, file.entries().size(), b.jobs.size(), b.coded, (unsigned long long)b.storedBytes,
      decoded, gpuMs, decoded / (gpuMs * 1e6), failed, mismatches(b, cpu, gpu));
  std::printf(
      "cpu_decode%s entries=%zu decodable=%zu coded=%zu stored_bytes=%llu decoded_bytes=%.0f "
      "threads=1 median_ms=%.3f gbps=%.2f\n",
      label, file.entries().size(), b.jobs.size(), b.coded, (unsigned long long)b.storedBytes,
      decoded, cpuMs, decoded / (cpuMs * 1e6));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_gpu_decode FILE.afam [--rounds N]\n");
    return 2;
  }
  int rounds = 5;
  for (int a = 2; a + 1 < argc; ++a)
    if (std::strcmp(argv[a], "--rounds") == 0) rounds = std::max(1, std::atoi(argv[a + 1]));
  std::string why;
  if (!gpuAvailable(&why)) {
    std::fprintf(stderr, "bench_gpu_decode: no usable GPU: %s\n", why.c_str());
    return 1;
  }
  try {
    const auto file = AfamFile::open(argv[1]);
    const gputest::StoredPayloads stored = gputest::readStoredPayloads(*file);
    const gputest::DecodeBatch all = gputest::decodableBatch(*file, stored);
    uint64_t storedAll = 0, lanesAll = 0;
    for (const ModelEntry& e : file->entries()) {
      storedAll += e.storedSize;
      lanesAll += e.lanesCoded;
    }
    std::printf("file %s: %zu entries, %llu stored bytes, %llu lanes frames; GPU %s\n", argv[1],
                file->entries().size(), (unsigned long long)storedAll, (unsigned long long)lanesAll,
                gpuDescription(0).c_str());
    gputest::DeviceBuffer payloads(stored.bytes.size());
    const auto t0 = std::chrono::steady_clock::now();
    payloads.upload(stored.bytes.data(), stored.bytes.size());
    std::printf(
        "upload of the stored payloads: %.3f ms (pageable memory)\n",
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    run(*file, stored, all, "", rounds, payloads);
    run(*file, stored, codedOnly(all), "_coded", rounds, payloads);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_gpu_decode: %s\n", e.what());
    return 1;
  }
  return 0;
}
