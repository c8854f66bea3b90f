// SPDX-License-Identifier: BSD-3-Clause
// The cache keeps integer-coded models in their compact form by default (cache.hpp): a frame drawn
// from them is the frame drawn from floats, bit for bit, and the cache holds fewer bytes.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "afam/encode/encoder.hpp"
#include "afam/render/renderer.hpp"
#include "afam/volume/enlarged_scan.hpp"
#include "head_mri.hpp"
#include "render_test_util.hpp"

using namespace afam;

namespace {

/// The repository's head MRI made four times as large with scan noise (afam enlarge's generator)
/// and encoded at 1e-2 of its range with the defaults: its blocks are integer-coded splines, as a
/// real scan's mostly are.
std::shared_ptr<const AfamFile> noisyScan() {
  const std::string path = afam_test::tempPath("compact_frames_scan");
  if (::access(path.c_str(), R_OK) != 0) {
    std::vector<float> v = afam_test::headMri();
    EnlargedScanSource src(std::move(v), {48, 62, 42}, {192, 248, 168}, 2.5, 1, 0, 255);
    EncoderOptions o;
    o.errorBound = 1e-2;
    o.relativeBound = true;
    o.threads = 2;
    encodeVolume(src, o, path);
  }
  return AfamFile::open(path);
}

}  // namespace

TEST(CompactFrames, TheCacheKeepsCodesAndTheFrameIsTheFloatsFrame) {
  const auto file = noisyScan();
  int64_t integer = 0;
  for (const ModelEntry& e : file->entries()) integer += e.integerCoded;
  ASSERT_GE(integer, 40);
  const afam_test::CompactAndFloats c = afam_test::drawCompactAndFloats(file, 80, 64);
  // The splines' control points take 1- or 2-byte codes: the cache holds under half the bytes.
  EXPECT_EQ(c.compactBlocks, c.floatBlocks);
  EXPECT_LT(2 * c.compactBytes, c.floatBytes) << c.compactBytes << " vs " << c.floatBytes;
}

TEST(CompactFrames, ACasterThatReadsFloatsOnlyGetsFloats) {
  // A caster that cannot read the compact form gets float32 models from the cache.
  class FloatsOnly : public CpuCaster {
   public:
    FloatsOnly() : CpuCaster(2) {}
    bool readsCompactForm() const override { return false; }
  };
  const auto file = noisyScan();
  RenderOptions o;
  o.threads = 2;
  o.lod.bandWidth = 100;
  const Camera cam = Camera::lookAt({1.2, 1.4, 1.0}, {0, 0, 0}, {0, 0, 1}, 50, 32, 32);
  Renderer compact(file, o), floats(file, o);
  floats.setCaster(std::make_unique<FloatsOnly>());
  FrameStats a, b;
  compact.renderFrame(cam, a);
  floats.renderFrame(cam, b);
  EXPECT_EQ(compact.cache().residentBlocks(), floats.cache().residentBlocks());
  EXPECT_LT(2 * compact.cache().residentBytes(), floats.cache().residentBytes());
}
