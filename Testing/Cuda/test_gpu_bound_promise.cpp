// SPDX-License-Identifier: BSD-3-Clause
// The bound-promise sweep through the GPU decoder: every file of the default suite's selection of
// the sweep (Testing/Core/bound_promise_cases.hpp: every small shape, scales 1e-30 to 1e30, both
// bound kinds, missing samples, runs of two steps) and the 2x2x2 volume that once decoded to 1e24,
// each encoded with the default entropy stage and with a lanes frame for every coded payload, and
// the sweep's thin slabs at every scale with lanes frames and with float32 control points.
// Every payload the GPU decodes (constants, float32 points, lanes-coded splines) and every block's
// compact form (what the pool expands) decode on the GPU to the floats the CPU reader gives, bit
// for bit, and the CPU reader's floats are within the bound on every block (decoded_bound.hpp):
// so the GPU's are.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "../Core/bound_promise_cases.hpp"
#include "../Core/decoded_bound.hpp"
#include "../Core/scratch_dir.hpp"
#include "afam/cuda/common/gpu_error.hpp"
#include "afam/cuda/decode/gpu_block_decoder.hpp"
#include "gpu_decode_batch.hpp"

namespace afam {
namespace {

using afam_test::PromiseCase;

/// What the GPU decoded of the sweep's files, summed.
struct Tally {
  size_t files = 0, refused = 0, jobs = 0, failed = 0, mismatches = 0;
  size_t kinds[4] = {0, 0, 0, 0};  ///< jobs by GpuDecodeKind
};

/// The file's decodable payloads and every block's compact form (appended after the stored
/// bytes) as one batch of jobs, and the entry of each job.
gputest::DecodeBatch batchWithCompactForms(const AfamFile& f, gputest::StoredPayloads& stored) {
  gputest::DecodeBatch batch = gputest::decodableBatch(f, stored);
  std::vector<float> compact;
  for (size_t i = 0; i < f.entries().size(); ++i) {
    const CompactForm form = f.readCompact(int64_t(i), 1.0, compact);
    if (form.width == 0) continue;
    const uint64_t at = stored.bytes.size();
    stored.bytes.resize(at + compact.size() * 4 + 4, 0);
    std::memcpy(stored.bytes.data() + at, compact.data(), compact.size() * 4);
    const ModelEntry& e = f.entries()[i];
    batch.jobs.push_back(gpuCompactJob(form, e.ncp, at, batch.outputFloats));
    batch.entries.push_back(i);
    batch.outputFloats += uint64_t(controlCount(e));
  }
  return batch;
}

/// Decodes the batch of one step's file on the GPU and compares each job with readPayload.
void decodeOnGpuAsTheCpu(const AfamFile& f, const std::string& name, Tally& t) {
  gputest::StoredPayloads stored = gputest::readStoredPayloads(f);
  const gputest::DecodeBatch batch = batchWithCompactForms(f, stored);
  if (batch.jobs.empty()) return;
  gputest::DeviceBuffer payloads(stored.bytes.size()), output(batch.outputFloats * 4 + 4);
  payloads.upload(stored.bytes.data(), stored.bytes.size());
  output.fill(0xff);  // NaN: a job that writes nothing differs
  GpuBlockDecoder decoder;
  const std::vector<uint32_t> status = decoder.decode(batch.jobs, payloads.data(), output.floats());
  std::vector<float> gpu(batch.outputFloats);
  output.download(gpu.data(), gpu.size() * 4);
  for (size_t k = 0; k < batch.jobs.size(); ++k) {
    ++t.jobs;
    ++t.kinds[int(batch.jobs[k].kind)];
    const std::vector<float> cpu = f.readPayload(int64_t(batch.entries[k]));
    const bool same =
        std::memcmp(cpu.data(), gpu.data() + batch.jobs[k].outputOffset, cpu.size() * 4) == 0;
    t.failed += status[k] != 0;
    t.mismatches += !same;
    EXPECT_TRUE(status[k] == 0 && same)
        << name << ": entry " << batch.entries[k] << " (job kind " << int(batch.jobs[k].kind)
        << ", status " << status[k] << ") decodes on the GPU to other floats than on the CPU";
  }
}

/// Encodes the case with `entropy`, checks every block within its bound as the CPU reads it and
/// every decodable payload on the GPU against the CPU.
void checkOnGpu(const PromiseCase& c, uint32_t seed, EntropyStage entropy, Tally& t,
                bool compact = true) {
  SCOPED_TRACE(c.name());
  const std::string path = afam_test::scratchPath("gpu_promise.afam");
  EncoderOptions opt = afam_test::optionsOf(c);
  opt.entropy = entropy;
  opt.compact = compact;
  const afam_test::EncodedCase e = afam_test::encodeCase(c, seed, opt, path);
  if (e.refused) {
    ++t.refused;
    return;
  }
  for (size_t step = 0; step < e.sources.size(); ++step) {
    auto f = AfamFile::open(path, int64_t(step));
    afam_test::expectEveryBlockWithinItsBound(*f, *e.sources[step]);
    decodeOnGpuAsTheCpu(*f, c.name() + " step " + std::to_string(step), t);
    ++t.files;
  }
  std::filesystem::remove(path);
}

void report(const char* what, const Tally& t) {
  std::printf(
      "[gpu-promise] %s: files %zu (refused %zu), GPU jobs %zu (constant %zu, float32 %zu, lanes "
      "coded %zu, compact %zu), failed %zu, mismatches %zu\n",
      what, t.files, t.refused, t.jobs, t.kinds[0], t.kinds[1], t.kinds[2], t.kinds[3], t.failed,
      t.mismatches);
}

TEST(GpuBoundPromise, TheSweepDecodesOnTheGpuAsOnTheCpu) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  for (const EntropyStage entropy : {EntropyStage::Auto, EntropyStage::Lanes}) {
    Tally t;
    afam_test::forEachDefaultCase(
        [&](const PromiseCase& c, uint32_t seed) { checkOnGpu(c, seed, entropy, t); });
    report(entropy == EntropyStage::Auto ? "default entropy" : "lanes frames", t);
    EXPECT_EQ(t.failed + t.mismatches, 0u);
    EXPECT_GT(t.files, 300u);
    // Small blocks end as constants and interpolants: on the GPU, constants and compact forms.
    EXPECT_GT(t.kinds[int(GpuDecodeKind::Constant)], 0u);
    EXPECT_GT(t.kinds[int(GpuDecodeKind::Compact)], 0u);
  }
}

TEST(GpuBoundPromise, ThinSlabsAtEveryScaleDecodeOnTheGpuAsOnTheCpu) {
  // The sweep's slabs (1-2 samples beside 64), smooth and noisy, at every scale and both bound
  // kinds: their splines reach the GPU's lanes-coded path (steps and bases from 1e-30 to 1e30)
  // and, with float32 control points, its copy path.
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  for (const bool compact : {true, false}) {
    Tally t;
    uint32_t seed = 3000;
    for (afam::Index3 d : afam_test::smallShapes()) {
      if (std::max({d[0], d[1], d[2]}) < 64) continue;
      for (const double scale : afam_test::kScales)
        for (const afam_test::Content content :
             {afam_test::Content::Smooth, afam_test::Content::Noise})
          for (const BoundKind kind : afam_test::kKinds)
            for (const double bound : {1e-2, 1e-4}) {
              const PromiseCase c{d, scale, content, kind, bound, false, false};
              checkOnGpu(c, seed++, EntropyStage::Lanes, t, compact);
            }
    }
    report(compact ? "thin slabs, lanes frames" : "thin slabs, float32 points", t);
    EXPECT_EQ(t.failed + t.mismatches, 0u);
    EXPECT_GT(t.files, 200u);
    EXPECT_GT(t.kinds[int(compact ? GpuDecodeKind::IntegerLorenzo : GpuDecodeKind::Floats)], 20u);
  }
}

TEST(GpuBoundPromise, TheVolumeThatDecodedTo1e24DecodesOnTheGpuAsOnTheCpu) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  std::vector<float> v = afam_test::theVolumeThatDecodedTo1e24();
  ArraySource src(v.data(), {2, 2, 2}, "v");
  const std::string path = afam_test::scratchPath("gpu_two.afam");
  Tally t;
  for (const double bound : afam_test::kBounds)
    for (const EntropyStage entropy : {EntropyStage::Auto, EntropyStage::Lanes}) {
      EncoderOptions opt;
      opt.errorBound = bound;
      opt.relativeBound = true;
      opt.entropy = entropy;
      encodeVolume(src, opt, path);
      auto f = AfamFile::open(path);
      afam_test::expectEveryBlockWithinItsBound(*f, src);
      decodeOnGpuAsTheCpu(*f, "2x2x2 at " + std::to_string(bound), t);
      ++t.files;
    }
  std::filesystem::remove(path);
  report("the 2x2x2 volume", t);
  EXPECT_EQ(t.failed + t.mismatches, 0u);
  EXPECT_GT(t.kinds[3], 0u) << "its rounded interpolant's compact form was not decoded on the GPU";
}

}  // namespace
}  // namespace afam
