// SPDX-License-Identifier: BSD-3-Clause
// The GPU's batched least-squares residuals (make_gpu_least_squares.hpp) against the CPU
// reference (least_squares_batch.hpp): the same doubles bit for bit on blocks of every shape the
// encoder makes (edges, slabs, one-sample axes) and degrees 1-3, a block too large for shared
// memory answered by the CPU; and an encode asked ahead on the GPU writes the file the CPU
// encoder writes, the same bytes twice.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include "../Core/file_bytes.hpp"
#include "../Core/noisy_block.hpp"
#include "../Core/scratch_dir.hpp"
#include "afam/cuda/common/gpu_error.hpp"
#include "afam/cuda/encode/make_gpu_least_squares.hpp"
#include "afam/cuda/encode/make_gpu_level_sampler.hpp"
#include "afam/encode/encoder.hpp"
#include "afam/spline/fit.hpp"
#include "afam/volume/enlarged_scan.hpp"

namespace afam {
namespace {

std::shared_ptr<LeastSquaresBatch> gpuBatch() {
  return makeGpuLeastSquares([](const std::string& why) { std::printf("gpu: %s\n", why.c_str()); });
}

TEST(GpuLeastSquares, ResidualsEqualTheCpuReferenceBitForBit) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  auto gpu = gpuBatch();
  ASSERT_TRUE(gpu);
  CpuLeastSquaresBatch cpu;
  const std::vector<Int3> shapes{{64, 64, 64}, {65, 64, 66}, {37, 64, 12}, {1, 40, 33},
                                 {2, 2, 2},    {64, 1, 64},  {150, 150, 4}};
  std::vector<std::vector<float>> blocks;
  std::vector<const float*> pointers;
  for (size_t b = 0; b < shapes.size(); ++b) {
    blocks.push_back(afam_test::smoothPlusNoise(shapes[b], 3.0, uint32_t(b)));
    pointers.push_back(blocks.back().data());
  }
  size_t compared = 0, different = 0;
  for (int degree : {1, 2, 3}) {
    gpu->setBlocks(pointers, shapes, degree);
    cpu.setBlocks(pointers, shapes, degree);
    std::vector<LsqRequest> requests;
    for (size_t b = 0; b < shapes.size(); ++b) {
      Int3 degs{};
      for (int a = 0; a < 3; ++a) degs[a] = effectiveDegree(degree, shapes[b][a]);
      for (int k : {1, 3, 9, 20, 33, 64, 150})
        requests.push_back({int32_t(b), clampNcp(k, shapes[b], degs)});
      requests.push_back({int32_t(b), shapes[b]});  // interpolation: residual ~0
    }
    std::vector<LsqResidual> g, c;
    gpu->residuals(requests, g);
    cpu.residuals(requests, c);
    ASSERT_EQ(g.size(), c.size());
    for (size_t r = 0; r < g.size(); ++r) {
      ++compared;
      const bool same = std::memcmp(&g[r], &c[r], sizeof(LsqResidual)) == 0;
      different += !same;
      EXPECT_TRUE(same) << "degree " << degree << " request " << r << ": gpu " << g[r].squares
                        << " / " << g[r].residual << ", cpu " << c[r].squares << " / "
                        << c[r].residual;
    }
  }
  std::printf("[gpu-lsq] residuals compared %zu, different %zu (%s)\n", compared, different,
              gpu->description().c_str());
}

/// The head MRI made large with noise: blocks of 64 samples, noisy and smooth ones.
std::vector<float> scan(Index3 dims) {
  const std::vector<char> bytes = afam_test::readAll(
      std::string(AFAM_SOURCE_DIR) + "/Testing/Data/volumes/HeadMRVolume_48x62x42_uint8.raw");
  std::vector<float> head(bytes.size());
  for (size_t i = 0; i < bytes.size(); ++i) head[i] = float(uint8_t(bytes[i]));
  EnlargedScanSource source(head, {48, 62, 42}, dims, 2.5, 1, 0, 255);
  std::vector<float> v(size_t(dims[0] * dims[1] * dims[2]));
  source.readSlab(0, dims[2], v.data());
  return v;
}

TEST(GpuLeastSquares, AnEncodeAskedAheadOnTheGpuWritesTheCpuEncodersFile) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  const Index3 dims{150, 194, 132};
  const std::vector<float> v = scan(dims);
  ArraySource src(v.data(), dims, "scan");
  auto encode = [&](std::shared_ptr<LeastSquaresBatch> batch, EncodeStats& stats) {
    EncoderOptions opt;
    opt.errorBound = 1e-2;
    opt.relativeBound = true;
    opt.leastSquares = std::move(batch);
    const std::string path = afam_test::scratchPath("gpu_ahead.afam");
    stats = encodeVolume(src, opt, path);
    std::vector<char> bytes = afam_test::readAll(path);
    std::remove(path.c_str());
    return bytes;
  };
  EncodeStats plain, once, twice;
  const std::vector<char> a = encode(nullptr, plain);
  auto gpu = gpuBatch();
  ASSERT_TRUE(gpu);
  const std::vector<char> b = encode(gpu, once);
  const std::vector<char> c = encode(gpu, twice);
  std::printf(
      "[gpu-lsq] encode %lldx%lldx%lld: fits %lld on the CPU, %lld asked ahead on the GPU "
      "(%lld residuals), %.3f s and %.3f s; %zu bytes\n",
      (long long)dims[0], (long long)dims[1], (long long)dims[2], (long long)plain.fits,
      (long long)once.fits, (long long)once.askedAhead, plain.seconds, once.seconds, a.size());
  EXPECT_TRUE(a == b) << "the GPU's verdicts changed the file";
  EXPECT_TRUE(b == c) << "two encodes on the GPU differ";
  EXPECT_GT(once.askedAhead, 0);
  EXPECT_LT(once.fits, plain.fits);
}

/// Boxes of a volume in a GPU level sampler's copy, asked of the GPU's batch as boxes
/// (setBlocksIn): the residuals of the same boxes' floats handed to the CPU reference.
template <typename T>
void expectBoxesAsTheirSamples(SampleType type, const char* name) {
  const Index3 dims{131, 97, 70};
  std::mt19937 rng(5);
  std::vector<T> volume(size_t(dims[0] * dims[1] * dims[2]));
  for (size_t i = 0; i < volume.size(); ++i)
    volume[i] = T(double(i % 131) * 0.7 + double((i / 131) % 97) * 0.5 + double(rng() % 40));
  auto sampler =
      makeGpuLevelSampler([](const std::string& why) { std::printf("%s\n", why.c_str()); });
  ASSERT_TRUE(sampler);
  std::string why;
  ASSERT_TRUE(sampler->reserve(dims, type, why)) << why;
  sampler->load(0, dims[2], volume.data());
  const std::vector<Index3> origins{{0, 0, 0}, {66, 32, 6}, {130, 0, 69}, {64, 33, 0}, {3, 90, 40}};
  const std::vector<Int3> shapes{
      {66, 64, 64}, {65, 65, 64}, {1, 97, 1}, {67, 64, 70}, {128, 7, 30}};
  std::vector<std::vector<float>> boxes(shapes.size());
  std::vector<const float*> pointers;
  for (size_t b = 0; b < shapes.size(); ++b) {
    const Int3 n = shapes[b];
    for (int z = 0; z < n[2]; ++z)
      for (int y = 0; y < n[1]; ++y)
        for (int x = 0; x < n[0]; ++x)
          boxes[b].push_back(float(volume[size_t(
              ((origins[b][2] + z) * dims[1] + origins[b][1] + y) * dims[0] + origins[b][0] + x)]));
    pointers.push_back(boxes[b].data());
  }
  auto gpu = gpuBatch();
  ASSERT_TRUE(gpu);
  CpuLeastSquaresBatch cpu;
  gpu->setBlocksIn(VolumeBoxes{sampler.get(), origins}, pointers, shapes, 2);
  cpu.setBlocks(pointers, shapes, 2);
  std::vector<LsqRequest> requests;
  for (size_t b = 0; b < shapes.size(); ++b)
    for (int k : {3, 9, 33, 64}) {
      Int3 ncp{};
      for (int a = 0; a < 3; ++a) ncp[a] = std::min(k, shapes[b][a]);
      requests.push_back({int32_t(b), ncp});
    }
  std::vector<LsqResidual> g, c;
  gpu->residuals(requests, g);
  cpu.residuals(requests, c);
  ASSERT_EQ(g.size(), c.size());
  size_t different = 0;
  for (size_t r = 0; r < g.size(); ++r)
    different += std::memcmp(&g[r], &c[r], sizeof(LsqResidual)) != 0;
  std::printf("[gpu-lsq] boxes of a %s copy: residuals compared %zu, different %zu\n", name,
              g.size(), different);
  EXPECT_EQ(different, 0u);
  EXPECT_GT(c[0].squares, 0.0);
}

TEST(GpuLeastSquares, BoxesOfTheVolumesCopyOnTheGpuGiveTheResidualsOfTheirSamples) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  expectBoxesAsTheirSamples<uint8_t>(SampleType::UInt8, "uint8");
  expectBoxesAsTheirSamples<int16_t>(SampleType::Int16, "int16");
  expectBoxesAsTheirSamples<float>(SampleType::Float32, "float32");
}

TEST(GpuLeastSquares, AnEncodeTakingTheFinestBlocksFromTheGpusCopyWritesTheCpuEncodersFile) {
  std::string why;
  if (!gpuAvailable(&why)) GTEST_SKIP() << "no usable GPU: " << why;
  const Index3 dims{150, 194, 132};
  const std::vector<float> v = scan(dims);
  std::vector<uint8_t> bytes(v.size());  // a scan as stored: the copy holds its bytes
  for (size_t i = 0; i < v.size(); ++i)
    bytes[i] = uint8_t(std::lround(std::clamp(v[i], 0.0f, 255.0f)));
  auto encode = [&](bool onGpu, EncodeStats& stats) {
    ArraySource src(bytes.data(), SampleType::UInt8, dims);
    EncoderOptions opt;
    opt.levels = 3;
    opt.blocksPerAxis = 3;
    opt.errorBound = 1e-2;
    opt.relativeBound = true;
    if (onGpu) {
      opt.leastSquares = gpuBatch();
      opt.levelSampler = makeGpuLevelSampler([](const std::string&) {});
    }
    const std::string path = afam_test::scratchPath("gpu_boxes.afam");
    stats = encodeVolume(src, opt, path);
    std::vector<char> file = afam_test::readAll(path);
    std::remove(path.c_str());
    return file;
  };
  EncodeStats plain, gpu;
  const std::vector<char> a = encode(false, plain), b = encode(true, gpu);
  std::printf("[gpu-lsq] encode from the GPU's copy (%s): %lld residuals, %zu bytes\n",
              gpu.levelSampler.c_str(), (long long)gpu.askedAhead, b.size());
  EXPECT_TRUE(a == b) << "the blocks from the GPU's copy changed the file";
  EXPECT_GT(gpu.askedAhead, 0);
  EXPECT_FALSE(gpu.levelSampler.empty());
  EXPECT_EQ(gpu.levelSampler.rfind("not used", 0), std::string::npos) << gpu.levelSampler;
}

}  // namespace
}  // namespace afam
