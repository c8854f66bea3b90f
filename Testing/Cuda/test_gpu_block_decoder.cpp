// SPDX-License-Identifier: BSD-3-Clause
// The GPU decoder (gpu_block_decoder.hpp) against Core's: files encoded with lanes frames decode
// on the GPU to the very floats AfamFile::readPayload gives, and damaged payloads are refused on
// the GPU exactly where the CPU refuses them, each in its own job, the others decoded intact.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

#include "../Core/head_mri.hpp"
#include "../Core/scratch_dir.hpp"
#include "afam/cuda/common/gpu_error.hpp"
#include "afam/cuda/decode/gpu_block_decoder.hpp"
#include "afam/encode/encoder.hpp"
#include "afam/entropy/lanes_coder.hpp"
#include "afam/format/block_codec.hpp"
#include "afam/volume/enlarged_scan.hpp"
#include "afam/volume/marschner_lobb.hpp"
#include "gpu_decode_batch.hpp"

namespace afam {
namespace {

using gputest::DeviceBuffer;

struct Scene {
  int n = 65, levels = 3, blocks = 4;
  double bound = 1e-3;     ///< relative
  float scale = 1;         ///< values times this: a larger range in steps, longer varints
  bool flatThird = false;  ///< the first third of the slices constant: constant blocks
  bool compact = true;     ///< false: float32 splines
};

/// `source` encoded with `o` at a relative bound, every coded payload in a lanes frame.
std::shared_ptr<const AfamFile> encodeInLanes(VolumeSource& source, EncoderOptions o,
                                              const std::string& name) {
  o.relativeBound = true;
  o.entropy = EntropyStage::Lanes;
  o.threads = 0;
  const std::string path = afam_test::scratchPath(name + ".afam");
  encodeVolume(source, o, path);
  return AfamFile::open(path);
}

/// Marschner-Lobb on n^3 points, encoded with every coded payload in a lanes frame.
std::shared_ptr<const AfamFile> encodeLanes(const std::string& name, const Scene& c) {
  const int n = c.n;
  std::vector<float> data(size_t(n) * n * n);
  MarschnerLobb ml;
  marschnerLobbSlab(ml, {n, n, n}, 0, n, data.data());
  for (float& v : data) v *= c.scale;
  if (c.flatThird) std::fill(data.begin(), data.begin() + ptrdiff_t(size_t(n) * n * (n / 3)), 0.5f);
  ArraySource source(data.data(), {n, n, n});
  EncoderOptions o;
  o.levels = c.levels;
  o.blocksPerAxis = c.blocks;
  o.errorBound = c.bound;
  o.compact = c.compact;
  return encodeInLanes(source, o, name);
}

/// The repository's head MRI made 96 x 124 x 84 with noise above the bound, encoded at 1e-2 with
/// lanes frames: its finest blocks are interpolants, their points rounded (rounded_points.hpp).
std::shared_ptr<const AfamFile> encodeNoisyHead(const std::string& name) {
  EnlargedScanSource source(afam_test::headMri(), {48, 62, 42}, {96, 124, 84}, 6.0, 1, 0, 255);
  EncoderOptions o;
  o.levels = 2;
  o.blocksPerAxis = 4;
  o.errorBound = 1e-2;
  return encodeInLanes(source, o, name);
}

/// Whether a lanes frame's varints hold a value of more than one byte (the parser's slow path).
bool hasLongVarints(const ModelEntry& e, const uint8_t* stored) {
  const uint8_t* frame = stored + kIntegerCodedHeaderBytes;
  const size_t bytes = e.storedSize - kIntegerCodedHeaderBytes;
  std::vector<uint8_t> v(lanes::frameSymbols(frame, bytes));
  const char* error = nullptr;
  if (lanes::decodeFrame(frame, bytes, v.data(), v.size(), &error) < 0) return false;
  for (const uint8_t b : v)
    if (b >= 0x80) return true;
  return false;
}

struct CpuResult {
  bool ok = false;
  std::vector<float> floats;
};

CpuResult decodeOnCpu(const ModelEntry& e, const uint8_t* stored) {
  CpuResult r;
  r.floats.assign(size_t(controlCount(e)), 0.0f);
  try {
    decodeStoredPayload(e, stored, r.floats.data(), "cpu");
    r.ok = true;
  } catch (const Error&) {
    r.ok = false;
  }
  return r;
}

constexpr uint64_t kAllShared = ~uint64_t(0);  // setSharedJobLimit: as many as fit

/// Decodes every decodable entry of `file` on the GPU and compares with readPayload. Coded jobs
/// of more than sharedLimit control points take the decoder's global-memory path.
/// The batch decoded on the GPU (output poisoned with NaN first): its status words, and the floats
/// in `gpu`.
std::vector<uint32_t> decodeOnGpu(const gputest::StoredPayloads& stored,
                                  const gputest::DecodeBatch& batch, uint64_t sharedLimit,
                                  std::vector<float>& gpu) {
  DeviceBuffer payloads(stored.bytes.size()), output(batch.outputFloats * 4);
  payloads.upload(stored.bytes.data(), stored.bytes.size());
  output.fill(0xff);
  GpuBlockDecoder decoder;
  decoder.setSharedJobLimit(sharedLimit);
  const std::vector<uint32_t> status =
      decoder.decode(batch.jobs, payloads.data(), output.floats(), nullptr);
  gpu.resize(batch.outputFloats);
  output.download(gpu.data(), gpu.size() * 4);
  return status;
}

void expectFileDecodesAsTheCpu(const AfamFile& file, size_t minimumCoded, bool wantLong,
                               uint64_t sharedLimit = kAllShared, size_t minimumRounded = 0) {
  const gputest::StoredPayloads stored = gputest::readStoredPayloads(file);
  const gputest::DecodeBatch batch = gputest::decodableBatch(file, stored);
  std::vector<float> gpu;
  const std::vector<uint32_t> status = decodeOnGpu(stored, batch, sharedLimit, gpu);
  size_t mismatches = 0, failed = 0, longOnes = 0, kinds[5] = {0, 0, 0, 0, 0}, rounded = 0;
  for (size_t k = 0; k < batch.jobs.size(); ++k) {
    ++kinds[int(batch.jobs[k].kind)];
    const size_t i = batch.entries[k];
    const ModelEntry& e = file.entries()[i];
    const std::vector<float> cpu = file.readPayload(int64_t(i));
    failed += status[k] != 0;
    mismatches +=
        std::memcmp(cpu.data(), gpu.data() + batch.jobs[k].outputOffset, cpu.size() * 4) != 0;
    if (batch.jobs[k].kind == GpuDecodeKind::IntegerLorenzo)
      longOnes += hasLongVarints(e, stored.of(i));
    rounded += batch.jobs[k].kind == GpuDecodeKind::Interpolant && batch.jobs[k].pointStep > 0;
  }
  std::printf(
      "[gpu-decode] %s (shared-memory limit %lld): entries %zu, decodable %zu (constant %zu, "
      "float32 %zu, lanes coded %zu, "
      "with long varints %zu, interpolants %zu, rounded %zu), floats %llu, failed %zu, "
      "mismatches %zu\n",
      file.path().c_str(), sharedLimit == kAllShared ? -1ll : (long long)sharedLimit,
      file.entries().size(), batch.jobs.size(), kinds[0], kinds[1], kinds[2], longOnes, kinds[4],
      rounded, (unsigned long long)batch.outputFloats, failed, mismatches);
  EXPECT_EQ(failed, 0u);
  EXPECT_EQ(mismatches, 0u);
  EXPECT_GE(batch.coded, minimumCoded);
  EXPECT_GE(rounded, minimumRounded);
  if (wantLong) {
    EXPECT_GT(longOnes, 0u);
  }
}

TEST(GpuBlockDecoder, DecodesLanesCodedFilesAsTheCpu) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  // Small blocks at three levels, some constant, some interpolants; the same
  // as float32 splines; blocks of ~48 samples whose payloads span several of the parser's chunks,
  // at a bound tight enough for residuals of several bytes.
  Scene small;
  small.flatThird = true;
  expectFileDecodesAsTheCpu(*encodeLanes("ml65", small), 10, false);
  small.compact = false;
  expectFileDecodesAsTheCpu(*encodeLanes("ml65_floats", small), 0, false);
  Scene large;
  large.n = 97;
  large.levels = 2;
  large.blocks = 2;
  large.bound = 2e-5;
  large.scale = 1000;
  const auto ml97 = encodeLanes("ml97", large);
  expectFileDecodesAsTheCpu(*ml97, 2, true);
  // The same through global memory, every job and then the larger ones (23k and 37k points).
  expectFileDecodesAsTheCpu(*ml97, 2, true, 0);
  expectFileDecodesAsTheCpu(*ml97, 2, true, 30000);
}

TEST(GpuBlockDecoder, FitsRoundedInterpolantsAsTheCpu) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  // A noisy scan's finest blocks: interpolants of 25 x 32 x 22 samples whose rounded points must
  // come out as the CPU's fit and rounding give them, bit for bit; through shared and global
  // memory.
  const auto head = encodeNoisyHead("noisy_head");
  expectFileDecodesAsTheCpu(*head, 10, false, kAllShared, 20);
  expectFileDecodesAsTheCpu(*head, 10, false, 0, 20);
}

TEST(GpuBlockDecoder, RefusesAnInterpolantWhoseResidualsPassItsThirtyTwoBits) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  // An interpolant's samples in the double interpolation form at a step so small that its
  // residuals need more than 32 bits (the encoder never writes one: float32 samples within a
  // bound stay below 2^31 steps): the CPU decodes it, the GPU's parser refuses it (Varint), which
  // the GPU caster answers by decoding it on the CPU (gpu_caster.cpp).
  const Int3 n{9, 8, 7};
  std::mt19937 rng(9);
  std::normal_distribution<double> noise(100, 10);
  std::vector<float> samples(size_t(n[0] * n[1] * n[2]));
  for (float& v : samples) v = float(noise(rng));
  std::vector<uint8_t> payload;
  std::vector<float> recon;
  ASSERT_TRUE(encodeValues(samples.data(), n, 1e-8, Predictor::Interpolation,
                           EntropyCoding{3, EntropyStage::Lanes}, payload, recon));
  ModelEntry e;
  e.kind = BlockKind::Interpolant;
  e.coded = true;
  e.lanesCoded = payloadIsLanesCoded(payload.data(), payload.size());
  e.ncp = e.samples = n;
  e.degree = {2, 2, 2};
  e.size = uint64_t(samples.size()) * 4;
  e.storedSize = payload.size();
  ASSERT_TRUE(e.lanesCoded);
  ASSERT_TRUE(gpuDecodable(e, payload.data()));
  const CpuResult cpu = decodeOnCpu(e, payload.data());
  EXPECT_TRUE(cpu.ok);
  payload.resize((payload.size() + 3) / 4 * 4 + 4, 0);
  DeviceBuffer payloads(payload.size()), output(samples.size() * 4);
  payloads.upload(payload.data(), payload.size());
  GpuBlockDecoder decoder;
  const std::vector<uint32_t> status =
      decoder.decode({gpuDecodeJob(e, payload.data(), 0, 0)}, payloads.data(), output.floats());
  ASSERT_EQ(status.size(), 1u);
  EXPECT_EQ(status[0], uint32_t(GpuDecodeStatus::Varint)) << gpuDecodeStatusText(status[0]);
}

/// A damaged copy of a payload: the stored bytes and the entry that describes them.
struct Damaged {
  ModelEntry entry;
  std::vector<uint8_t> bytes;
  std::string what;
};

/// Sets a damaged copy's first lane state below 2^16 (where parseFrame says the states lie).
void lowerFirstState(Damaged& d) {
  uint32_t frequency[256];
  const uint8_t* frame = d.bytes.data() + kIntegerCodedHeaderBytes;
  const lanes::FrameLayout f =
      lanes::parseFrame(frame, d.bytes.size() - kIntegerCodedHeaderBytes, frequency);
  if (f.error) return;
  std::memset(d.bytes.data() + kIntegerCodedHeaderBytes + f.statesAt + 2, 0, 2);
}

std::vector<Damaged> damagedCopies(const AfamFile& file, const gputest::StoredPayloads& stored,
                                   const gputest::DecodeBatch& batch) {
  std::vector<Damaged> out;
  std::mt19937 random(7);
  std::vector<size_t> coded;
  for (size_t k = 0; k < batch.jobs.size(); ++k)
    if (batch.jobs[k].kind == GpuDecodeKind::IntegerLorenzo ||
        batch.jobs[k].kind == GpuDecodeKind::Interpolant)
      coded.push_back(batch.entries[k]);
  const auto copy = [&](size_t i, const std::string& what) {
    const ModelEntry& e = file.entries()[i];
    Damaged d{e, std::vector<uint8_t>(stored.of(i), stored.of(i) + e.storedSize), what};
    return d;
  };
  const size_t frameAt = kIntegerCodedHeaderBytes;
  for (size_t c = 0; c < std::min<size_t>(coded.size(), 12); ++c) {
    const size_t i = coded[c];
    Damaged d = copy(i, "last word flipped");
    d.bytes.back() ^= 0x5a;
    out.push_back(d);
    for (size_t cut : {1, 2, 5}) {
      d = copy(i, "truncated by " + std::to_string(cut));
      d.bytes.resize(d.bytes.size() - std::min(cut, d.bytes.size() - frameAt - 10));
      d.entry.storedSize = d.bytes.size();
      out.push_back(d);
    }
    d = copy(i, "V plus one");
    d.bytes[frameAt + 4] += 1;
    out.push_back(d);
    d = copy(i, "V minus one");
    d.bytes[frameAt + 4] -= 1;
    out.push_back(d);
    d = copy(i, "no lanes");
    d.bytes[frameAt + 8] = 0;
    out.push_back(d);
    d = copy(i, "negative step");
    d.bytes[7] ^= 0x80;
    out.push_back(d);
    d = copy(i, "base beyond 2^52");
    d.bytes[9 + 7] = 0x40;
    out.push_back(d);
    d = copy(i, "a frequency changed");
    d.bytes[frameAt + 10] ^= 0x01;
    out.push_back(d);
    d = copy(i, "a state below 2^16");
    lowerFirstState(d);
    out.push_back(d);
  }
  for (int t = 0; t < 400; ++t) {  // random flips anywhere in a coded payload
    const size_t i = coded[random() % coded.size()];
    Damaged d = copy(i, "random flip");
    d.bytes[random() % d.bytes.size()] ^= uint8_t(1u << (random() % 8));
    out.push_back(d);
  }
  return out;
}

/// Damaged copies of a file's coded payloads decoded in one batch after its intact jobs.
void expectDamageRefusedAsOnTheCpu(const std::shared_ptr<const AfamFile>& file,
                                   uint64_t sharedLimit) {
  gputest::StoredPayloads stored = gputest::readStoredPayloads(*file);
  gputest::DecodeBatch batch = gputest::decodableBatch(*file, stored);
  ASSERT_GT(batch.coded, 0u);
  std::vector<Damaged> damaged = damagedCopies(*file, stored, batch);
  // The intact jobs first, then every damaged payload appended to the same buffers.
  const size_t intactJobs = batch.jobs.size();
  std::vector<bool> routed(damaged.size(), false);
  for (size_t k = 0; k < damaged.size(); ++k) {
    Damaged& d = damaged[k];
    const uint64_t at = stored.bytes.size();
    stored.bytes.resize(at + (d.bytes.size() + 3) / 4 * 4 + 4, 0);
    std::memcpy(stored.bytes.data() + at, d.bytes.data(), d.bytes.size());
    routed[k] = gpuDecodable(d.entry, d.bytes.data());  // else the host keeps it on the CPU
    batch.jobs.push_back(gpuDecodeJob(d.entry, d.bytes.data(), at, batch.outputFloats));
    batch.outputFloats += uint64_t(controlCount(d.entry));
  }
  std::vector<float> gpu;
  const std::vector<uint32_t> status = decodeOnGpu(stored, batch, sharedLimit, gpu);
  size_t intactWrong = 0;
  for (size_t k = 0; k < intactJobs; ++k) {
    const std::vector<float> cpu = file->readPayload(int64_t(batch.entries[k]));
    intactWrong +=
        status[k] != 0 ||
        std::memcmp(cpu.data(), gpu.data() + batch.jobs[k].outputOffset, cpu.size() * 4) != 0;
  }
  EXPECT_EQ(intactWrong, 0u) << "intact jobs decoded wrongly next to damaged ones";
  size_t refused = 0, accepted = 0, kept = 0, disagree = 0, differ = 0;
  for (size_t k = 0; k < damaged.size(); ++k) {
    const GpuDecodeJob& job = batch.jobs[intactJobs + k];
    const uint32_t s = status[intactJobs + k];
    const Damaged& d = damaged[k];
    if (!routed[k]) {
      ++kept;
      continue;
    }
    const CpuResult cpu = decodeOnCpu(d.entry, d.bytes.data());
    if (cpu.ok != (s == 0)) {
      ++disagree;
      ADD_FAILURE() << d.what << ": CPU " << (cpu.ok ? "decodes" : "refuses") << ", GPU says "
                    << gpuDecodeStatusText(s);
      continue;
    }
    if (cpu.ok) {
      ++accepted;
      differ +=
          std::memcmp(cpu.floats.data(), gpu.data() + job.outputOffset, cpu.floats.size() * 4) != 0;
    } else {
      ++refused;
    }
  }
  std::printf(
      "[gpu-decode-damage] shared-memory limit %lld, damaged payloads %zu: refused by both %zu, "
      "decoded by both %zu (floats "
      "differing %zu), kept on the CPU %zu, disagreements %zu\n",
      sharedLimit == kAllShared ? -1ll : (long long)sharedLimit, damaged.size(), refused, accepted,
      differ, kept, disagree);
  EXPECT_EQ(disagree, 0u);
  EXPECT_EQ(differ, 0u);
  EXPECT_GT(refused, damaged.size() / 2);
}

TEST(GpuBlockDecoder, DamagedPayloadsAreRefusedWhereTheCpuRefusesThem) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  Scene scene;
  scene.flatThird = true;
  const auto ml65 = encodeLanes("ml65_damaged", scene);
  expectDamageRefusedAsOnTheCpu(ml65, kAllShared);
  expectDamageRefusedAsOnTheCpu(ml65, 0);  // the global-memory path
  expectDamageRefusedAsOnTheCpu(encodeNoisyHead("noisy_head_damaged"), kAllShared);  // interpolants
}

}  // namespace
}  // namespace afam

namespace afam {

TEST(GpuBlockDecoder, ExpandsCompactModelsAsTheHostAndRefusesACodePastTheTable) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  // Two models in a cache's compact form, 1- and 2-byte codes, side by side in one payload
  // buffer; then the second with a code past its table.
  std::mt19937 rng(5);
  const Int3 ncp{40, 40, 40};  // enough points for a 3000-value table to pay
  const uint64_t count = 40 * 40 * 40;
  std::vector<uint8_t> payloads;
  std::vector<GpuDecodeJob> jobs;
  std::vector<std::vector<float>> forms;
  std::vector<CompactForm> shapes;
  for (const int64_t span : {200, 3000}) {
    std::vector<int32_t> k(count);
    for (int32_t& v : k) v = int32_t(rng() % uint32_t(span)) - 7;
    std::vector<float> form;
    const CompactForm f = packCompact(
        k.data(), count, 0.75, [](int64_t v) { return float(double(v) * 0.37); }, form);
    ASSERT_EQ(f.width, span <= 256 ? 1 : 2);
    jobs.push_back(gpuCompactJob(f, ncp, payloads.size(), count * jobs.size()));
    EXPECT_EQ(jobs.back().storedBytes, form.size() * 4);
    const auto* bytes = reinterpret_cast<const uint8_t*>(form.data());
    payloads.insert(payloads.end(), bytes, bytes + form.size() * 4);
    payloads.resize((payloads.size() + 255) & ~size_t(255));
    forms.push_back(form);
    shapes.push_back(f);
  }
  auto run = [&](std::vector<float>& out) {
    DeviceBuffer device(payloads.size()), output(2 * count * 4);
    device.upload(payloads.data(), payloads.size());
    output.fill(0xff);
    GpuBlockDecoder decoder;
    const std::vector<uint32_t> status =
        decoder.decode(jobs, device.data(), output.floats(), nullptr);
    out.resize(2 * count);
    output.download(out.data(), out.size() * 4);
    return status;
  };
  std::vector<float> gpu;
  std::vector<uint32_t> status = run(gpu);
  for (size_t j = 0; j < 2; ++j) {
    EXPECT_EQ(status[j], 0u) << gpuDecodeStatusText(status[j]);
    std::vector<float> want(count);
    expandCompact(forms[j].data(), shapes[j], count, want.data());
    EXPECT_EQ(0, std::memcmp(want.data(), gpu.data() + j * count, count * 4)) << "job " << j;
  }
  // The second model's 100th code set past its table (2-byte codes, little-endian).
  const uint64_t at = jobs[1].payloadOffset + 4 * uint64_t(shapes[1].table) + 2 * 100;
  payloads[at] = 0xff;
  payloads[at + 1] = 0xff;
  status = run(gpu);
  EXPECT_EQ(status[0], 0u);
  EXPECT_EQ(status[1], uint32_t(GpuDecodeStatus::Range)) << gpuDecodeStatusText(status[1]);
}

}  // namespace afam
