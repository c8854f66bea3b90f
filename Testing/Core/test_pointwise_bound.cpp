// SPDX-License-Identifier: BSD-3-Clause
// A pointwise bound (BoundKind::MaxError, `afam encode --max-error`): every sample of every level
// within the bound as a reader decodes it, where an RMSE bound of the same size leaves samples
// further off; the file is version 3 and says what it keeps; runs keep it at every step; modes
// that promise nothing and version-2 writers refuse it.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/encode/encode_run.hpp"
#include "afam/encode/encoder.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/render/level_decode.hpp"
#include "moving_blob.hpp"
#include "scratch_dir.hpp"

using namespace afam;

namespace {

const Index3 kDims{40, 36, 30};
constexpr double kBound = 0.5;  // 2.5 noise sigmas: splines cannot follow every sample

EncoderOptions options(BoundKind kind) {
  EncoderOptions opt;
  opt.levels = 2;
  opt.blocksPerAxis = 3;
  opt.errorBound = kBound;
  opt.boundKind = kind;
  return opt;
}

/// The largest |decoded - truth| over the finest level of step s.
double worstSample(const std::string& path, int64_t s, const std::vector<float>& truth) {
  auto f = AfamFile::open(path, s);
  std::vector<float> out(truth.size());
  decodeLevelBox(*f, f->header().levels - 1, {0, 0, 0}, {kDims[0] - 1, kDims[1] - 1, kDims[2] - 1},
                 out.data());
  double worst = 0;
  for (size_t i = 0; i < out.size(); ++i)
    worst = std::max(worst, std::fabs(double(out[i]) - double(truth[i])));
  return worst;
}

}  // namespace

TEST(PointwiseBound, EverySampleOfEveryLevelIsWithinTheBound) {
  const std::vector<float> v = afam_test::movingBlob(kDims, 0);
  const std::string point = afam_test::scratchPath("pointwise.afam");
  const std::string rmse = afam_test::scratchPath("rmse.afam");
  ArraySource source(v.data(), kDims);
  const EncodeStats ps = encodeVolume(source, options(BoundKind::MaxError), point);
  encodeVolume(source, options(BoundKind::Rmse), rmse);
  auto f = AfamFile::open(point);
  EXPECT_EQ(f->version(), 3u) << "a pointwise bound is a field of version 3";
  EXPECT_EQ(f->stepCount(), 1);
  EXPECT_EQ(f->header().boundKind, BoundKind::MaxError);
  EXPECT_EQ(AfamFile::open(rmse)->version(), 2u) << "RMSE files are as before";
  for (const ModelEntry& e : f->entries())  // every level, against its own samples
    EXPECT_LE(e.maxError, kBound * (1 + 1e-6)) << Partition::blockName(e.level, e.block);
  EXPECT_LE(ps.maxError, kBound * (1 + 1e-6));
  EXPECT_LE(worstSample(point, 0, v), kBound * (1 + 1e-6)) << "as a reader decodes it";
  EXPECT_GT(worstSample(rmse, 0, v), kBound * 1.2) << "an RMSE bound lets samples further off";
}

TEST(PointwiseBound, ARunKeepsItAtEveryStep) {
  std::vector<std::vector<float>> values;
  for (int k = 0; k < 4; ++k) values.push_back(afam_test::movingBlob(kDims, k));
  afam_test::InMemoryRun run(kDims, std::move(values));
  const std::string path = afam_test::scratchPath("pointwise_run.afam");
  const RunStats st = encodeRun(run.steps, options(BoundKind::MaxError), RunOptions{}, path);
  int64_t references = 0;
  for (int64_t s = 0; s < 4; ++s) {
    references += st.references[size_t(s)];
    EXPECT_LE(worstSample(path, s, run.data[size_t(s)]), kBound * (1 + 1e-6)) << "step " << s;
    auto f = AfamFile::open(path, s);
    EXPECT_EQ(f->header().boundKind, BoundKind::MaxError);
    for (const ModelEntry& e : f->entries()) EXPECT_LE(e.maxError, kBound * (1 + 1e-6));
  }
  EXPECT_GT(references, 0) << "blocks the blob did not cross stay references";
}

TEST(PointwiseBound, ModesThatPromiseNothingAndVersionTwoWritersRefuseIt) {
  const std::vector<float> v = afam_test::movingBlob(kDims, 0);
  ArraySource source(v.data(), kDims);
  EncoderOptions fixed = options(BoundKind::MaxError);
  fixed.mode = EncodingMode::Fixed;
  const std::string path = afam_test::scratchPath("refused.afam");
  try {
    encodeVolume(source, fixed, path);
    FAIL() << "a fixed-NCP encode took a pointwise bound";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("bounded mode"), std::string::npos) << e.what();
  }
  VolumeHeader h;
  h.dims = kDims;
  h.boundKind = BoundKind::MaxError;
  EXPECT_THROW(AfamWriter(path, h), InvalidArgument);
  EXPECT_FALSE(std::filesystem::exists(path));
}
