// SPDX-License-Identifier: BSD-3-Clause
// The cache's stored form (cache.hpp), as a caster that decodes payloads itself asks for it: the
// models it names are kept as their CRC-checked payloads (the budget counts those bytes), a frame
// cast on the CPU after all decodes them and draws the image the decoded cache draws, bit for bit;
// models such a caster reports damaged are recorded, reported once and stood in for.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "afam/encode/encoder.hpp"
#include "afam/render/renderer.hpp"
#include "render_test_util.hpp"

using namespace afam;

namespace {

std::shared_ptr<const AfamFile> noisyFile() {
  return afam_test::encodeNoisyField(EntropyStage::Lanes);
}

bool codedOrConstant(const ModelEntry& e) { return e.coded || e.kind == BlockKind::Constant; }

/// The CPU's caster, asking for the stored form; it may report one entry damaged.
class StoredFormCaster : public CpuCaster {
 public:
  StoredFormCaster() : CpuCaster(2) {}
  CastResult cast(const PreparedFrame& frame, const FrameTargets& targets,
                  ImageRGBA& image) override {
    for (size_t s = 0; s < frame.models.size(); ++s) stored += frame.models[s]->isStored();
    CastResult r = CpuCaster::cast(frame, targets, image);
    if (reportDamaged >= 0) r.damaged.push_back({reportDamaged, "decoded into nonsense"});
    reportDamaged = -1;
    return r;
  }
  bool readsHostPool() const override { return false; }
  StoredForm storedForm() const override { return &codedOrConstant; }
  int64_t stored = 0;
  int64_t reportDamaged = -1;
};

RenderOptions options() {
  RenderOptions o;
  o.threads = 2;
  o.loadThreads = 2;
  o.sampleDistance = 0.01f;
  o.cache = CacheBudget{};
  o.lod.bandWidth = 100;  // every block finest
  o.transferFunction.colors = {{0.0, 0.2, 0.4, 0.9}, {1.0, 1.0, 0.8, 0.2}};
  o.transferFunction.opacities = {{0.0, 0.0}, {0.3, 0.0}, {1.0, 0.9}};
  return o;
}

Camera camera() { return Camera::lookAt({1.2, 1.4, 1.0}, {0, 0, 0}, {0, 0, 1}, 50, 64, 64); }

}  // namespace

TEST(StoredForm, DecodedWhereCastOnTheCpuAndTheSameImage) {
  const auto file = noisyFile();
  int64_t lanes = 0;
  for (const ModelEntry& e : file->entries()) lanes += e.lanesCoded;
  ASSERT_GT(lanes, 8);
  RenderOptions asFloats = options();
  asFloats.compactModels = false;  // the float32 models, which the stored bytes are against
  Renderer plain(file, asFloats);
  FrameStats a, b;
  const ImageRGBA want = plain.renderFrame(camera(), a);
  Renderer held(file, options());
  auto caster = std::make_unique<StoredFormCaster>();
  StoredFormCaster* c = caster.get();
  held.setCaster(std::move(caster));
  const ImageRGBA got = held.renderFrame(camera(), b);
  ASSERT_EQ(want.rgba.size(), got.rgba.size());
  EXPECT_EQ(0, std::memcmp(want.rgba.data(), got.rgba.data(), want.rgba.size() * sizeof(float)));
  EXPECT_GT(c->stored, 8);  // models the frame took in the stored form
  // The budget counts the stored bytes: the held cache is several times smaller.
  EXPECT_LT(3 * held.cache().residentBytes(), plain.cache().residentBytes())
      << held.cache().residentBytes() << " vs " << plain.cache().residentBytes();
  // Back to the CPU's caster: models loaded from now on are floats, the stored ones still draw.
  held.setCaster(nullptr);
  FrameStats s;
  const ImageRGBA again = held.renderFrame(camera(), s);
  EXPECT_EQ(0, std::memcmp(want.rgba.data(), again.rgba.data(), want.rgba.size() * sizeof(float)));
}

TEST(StoredForm, AModelTheCasterFindsDamagedIsReportedOnceAndStoodInFor) {
  const auto file = noisyFile();
  Renderer r(file, options());
  auto caster = std::make_unique<StoredFormCaster>();
  StoredFormCaster* c = caster.get();
  r.setCaster(std::move(caster));
  FrameStats s1, s2, s3;
  r.renderFrame(camera(), s1);
  // A coded finest block the frame drew.
  const Partition& p = file->partition();
  int64_t victim = -1;
  for (int64_t e = file->levelStart(p.levels() - 1); e < int64_t(file->entries().size()); ++e)
    if (file->entries()[size_t(e)].coded && r.cache().contains(e)) victim = e;
  ASSERT_GE(victim, 0);
  c->reportDamaged = victim;
  r.renderFrame(camera(), s2);
  ASSERT_EQ(s2.damageReports.size(), 1u);
  EXPECT_NE(s2.damageReports[0].find("decoded into nonsense"), std::string::npos)
      << s2.damageReports[0];
  r.renderFrame(camera(), s3);
  EXPECT_TRUE(s3.damageReports.empty());
  EXPECT_GE(s3.damagedBlocks, 1);
  EXPECT_EQ(s3.emptyDamagedBlocks, 0);  // its coarser model stands in
}
