// SPDX-License-Identifier: BSD-3-Clause
// Missing samples from a real file (issue 30): Marschner-Lobb with a CT's circular field of view
// cut out (MaskedSource FieldOfView), encoded and drawn by the Renderer on the CPU. Rays that cross
// only missing samples stay background, the empty blocks are culled (the frame's statistics count
// them), NaN opacity 1 draws the missing region in the NaN colour; decodeLevelBox gives NaN
// exactly at the missing samples of every level.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/encode/encoder.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/format/block_decode.hpp"
#include "afam/render/level_decode.hpp"
#include "afam/render/raycast.hpp"
#include "afam/render/renderer.hpp"
#include "afam/sampling/block_sampling.hpp"
#include "afam/volume/marschner_lobb.hpp"
#include "afam/volume/masked_volumes.hpp"
#include "render_test_util.hpp"
#include "scratch_dir.hpp"

using namespace afam;

namespace {

const Index3 kDims{41, 41, 37};
constexpr int kLevels = 2, kFinest = kLevels - 1;

/// Marschner-Lobb on kDims with the field of view cut out, as NaN.
struct MaskedMl {
  std::vector<float> samples;
  VolumeMask mask{MaskShape::FieldOfView, kDims};
  MaskedMl() : samples(size_t(kDims[0] * kDims[1] * kDims[2])) {
    std::vector<float> ml(samples.size());
    marschnerLobbSlab(MarschnerLobb{}, kDims, 0, kDims[2], ml.data());
    ArraySource inner(ml.data(), kDims);
    MaskedSource masked(inner, mask);
    masked.readSlab(0, kDims[2], samples.data());
  }
};

const MaskedMl& volume() {
  static const MaskedMl v;
  return v;
}

/// The masked volume encoded once per process: 8 finest blocks per axis leave the corner columns
/// of blocks outside the field of view (empty).
std::shared_ptr<const AfamFile> maskedFile() {
  static std::shared_ptr<const AfamFile> file;
  if (!file) {
    ArraySource source(volume().samples.data(), kDims);
    EncoderOptions o;
    o.levels = kLevels;
    o.blocksPerAxis = 8;
    o.errorBound = 1e-2;
    o.threads = 2;
    const std::string path = afam_test::tempPath("missing_fov");
    encodeVolume(source, o, path);
    file = AfamFile::open(path);
  }
  return file;
}

int64_t emptyBlocksOf(const AfamFile& f, int level) {
  int64_t n = 0;
  const Partition& p = f.partition();
  for (int64_t b = 0; b < p.blockCount(level); ++b)
    n += f.entries()[size_t(f.entryIndex(level, p.blockFromLinear(level, b)))].kind ==
                 BlockKind::Empty
             ? 1
             : 0;
  return n;
}

/// Straight down the field of view's axis, every block at the finest level.
Camera downTheAxis() {
  return Camera::parallelLookAt({0, 0, 3}, {0, 0, 0}, {0, 1, 0}, 1.1, 72, 72);
}

RenderOptions finestOptions(double nanOpacity) {
  RenderOptions o;
  o.threads = 2;
  o.sampleDistance = 0.01f;
  o.lod.forceLevel = kFinest;
  o.hasTransferFunction = true;
  o.transferFunction = afam_test::ramp(0.0, 1.0, 0.3, 0.9);
  o.transferFunction.nanColor = {0.1, 0.8, 0.3};
  o.transferFunction.nanOpacity = nanOpacity;
  return o;
}

/// Whether every sample a pixel's ray takes has only missing samples around it (the 8 corners of
/// its voxel cell): false also for a ray that takes no sample.
bool onlyMissingOnRay(const FrameView& f, int px, int py) {
  RaySamples r;
  if (!raySamples(f, px, py, r) || r.kEnd < r.kBegin) return false;
  const VolumeMask& mask = volume().mask;
  for (int64_t k = r.kBegin; k <= r.kEnd; ++k) {
    const float t = sampleAt(r, k);
    int64_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      const float v = (r.o[a] + t * r.d[a] - f.boxLo[a]) * f.voxelPerUnit[a];
      const float c = std::min(std::max(v, 0.f), f.voxelMax[a]);
      lo[a] = int64_t(std::floor(c));
      hi[a] = std::min<int64_t>(int64_t(std::ceil(c)), kDims[a] - 1);
    }
    for (int corner = 0; corner < 8; ++corner)
      if (!mask.missing(corner & 1 ? hi[0] : lo[0], corner & 2 ? hi[1] : lo[1],
                        corner & 4 ? hi[2] : lo[2]))
        return false;
  }
  return true;
}

std::vector<size_t> missingOnlyPixels(Renderer& r, const Camera& c) {
  PreparedFrame frame;
  r.prepareEmpty(c, frame);
  std::vector<size_t> out;
  for (int y = 0; y < c.height; ++y)
    for (int x = 0; x < c.width; ++x)
      if (onlyMissingOnRay(frame.view, x, y))
        out.push_back(size_t(y) * size_t(c.width) + size_t(x));
  return out;
}

}  // namespace

TEST(MissingFileRender, RaysThroughMissingSamplesOnlyStayBackgroundAndEmptyBlocksAreCulled) {
  auto file = maskedFile();
  ASSERT_EQ(file->header().missing, MissingKind::NaN);
  const int64_t empty = emptyBlocksOf(*file, kFinest);
  ASSERT_GE(empty, 4 * 7) << "the four corner columns of blocks, at every depth";
  Renderer r(file, finestOptions(0.0));
  const Camera c = downTheAxis();
  FrameStats st;
  const ImageRGBA image = r.renderFrame(c, st);
  EXPECT_EQ(st.culled.emptyBlocks, empty);  // every finest block is in view: all empty ones culled
  const std::vector<size_t> background = missingOnlyPixels(r, c);
  ASSERT_GT(background.size(), 300u) << "the corners of the image, outside the field of view";
  for (size_t p : background)
    for (int k = 0; k < 4; ++k) ASSERT_EQ(image.rgba[p * 4 + k], 0.f) << "pixel " << p;
  int drawn = 0;  // the field of view itself is drawn
  for (size_t p = 0; p < size_t(c.width * c.height); ++p) drawn += image.rgba[p * 4 + 3] > 0.05f;
  std::printf("[missing file] empty blocks %lld culled %lld, %zu missing-only pixels, %d drawn\n",
              (long long)empty, (long long)st.culled.emptyBlocks, background.size(), drawn);
  EXPECT_GT(drawn, 1500);
}

TEST(MissingFileRender, NanOpacityOneDrawsTheMissingRegionInTheNanColour) {
  // With a transfer function of the user's, and with the file's preset (no table given), which
  // keeps the NaN colour and opacity given with it.
  auto file = maskedFile();
  for (const bool preset : {false, true}) {
    SCOPED_TRACE(preset ? "preset table" : "given table");
    RenderOptions o = finestOptions(1.0);
    o.hasTransferFunction = !preset;
    Renderer r(file, o);
    const Camera c = downTheAxis();
    FrameStats st;
    const ImageRGBA image = r.renderFrame(c, st);
    EXPECT_EQ(st.culled.emptyBlocks, 0);  // drawn now: empty blocks are sampled (all NaN)
    const std::vector<size_t> missing = missingOnlyPixels(r, c);
    ASSERT_GT(missing.size(), 300u);
    for (size_t p : missing) {
      for (int k = 0; k < 3; ++k)
        ASSERT_NEAR(image.rgba[p * 4 + k], float(o.transferFunction.nanColor[size_t(k)]), 1e-5f)
            << "pixel " << p;
      ASSERT_NEAR(image.rgba[p * 4 + 3], 1.f, 1e-5f) << "pixel " << p;
    }
  }
  RenderOptions bad = finestOptions(1.5);
  bad.hasTransferFunction = false;
  EXPECT_THROW(Renderer(file, bad), InvalidArgument);
}

TEST(MissingFileRender, DecodedLevelsAreNaNExactlyAtTheMissingSamples) {
  auto file = maskedFile();
  const Partition& part = file->partition();
  ArraySource source(volume().samples.data(), kDims);
  BlockRowReader sampler(source, part);  // the encoder's samples of each level: its mask
  for (int l = 0; l < part.levels(); ++l) {
    const LevelGrid grid = levelGrid(part, l);
    const Index3 n = grid.dims;
    std::vector<float> decoded(size_t(n[0] * n[1] * n[2]));
    decodeLevelBox(*file, l, {0, 0, 0}, {n[0] - 1, n[1] - 1, n[2] - 1}, decoded.data());
    std::vector<char> expected(decoded.size(), 0);  // 1: the level's sample is missing
    const Int3 nb = part.blocksPerAxis(l);
    std::vector<std::vector<float>> row;
    for (int kz = 0; kz < nb[2]; ++kz) {
      sampler.readRow(l, kz, false, file->header().sampling, row);
      for (int j = 0; j < nb[1]; ++j)
        for (int i = 0; i < nb[0]; ++i) {
          const BlockExtent e = part.extent(l, {i, j, kz});
          const std::vector<float>& s = row[size_t(j * nb[0] + i)];
          const int64_t x0 = grid.start[0][size_t(i)], y0 = grid.start[1][size_t(j)],
                        z0 = grid.start[2][size_t(kz)];
          size_t q = 0;
          for (int z = 0; z < e.samples[2]; ++z)
            for (int y = 0; y < e.samples[1]; ++y)
              for (int x = 0; x < e.samples[0]; ++x, ++q)
                expected[size_t(((z0 + z) * n[1] + y0 + y) * n[0] + x0 + x)] =
                    std::isnan(s[q]) ? 1 : 0;
        }
    }
    int64_t wrong = 0, missing = 0;
    for (size_t i = 0; i < decoded.size(); ++i) {
      missing += expected[i];
      wrong += (std::isnan(decoded[i]) ? 1 : 0) != expected[i] ? 1 : 0;
    }
    EXPECT_EQ(wrong, 0) << "level " << l;
    EXPECT_GT(missing, int64_t(decoded.size()) / 10) << "level " << l;
    if (l == kFinest) {  // the finest level is the input's own grid: its NaN exactly
      ASSERT_EQ(decoded.size(), volume().samples.size());
      int64_t differ = 0;
      for (size_t i = 0; i < decoded.size(); ++i)
        differ += std::isnan(decoded[i]) != std::isnan(volume().samples[i]) ? 1 : 0;
      EXPECT_EQ(differ, 0);
    }
  }
}
