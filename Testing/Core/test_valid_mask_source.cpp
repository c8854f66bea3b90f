// SPDX-License-Identifier: BSD-3-Clause
// ValidMaskSource (a vtkValidPointMask-style byte mask, 0 = missing): the samples it reads are NaN
// exactly where the mask is 0, by planes and by rows, and a volume encoded through it is the file
// of the same volume with NaN written at those samples, byte for byte.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "afam/encode/encoder.hpp"
#include "afam/volume/valid_mask_source.hpp"
#include "file_bytes.hpp"
#include "moving_blob.hpp"
#include "scratch_dir.hpp"

using namespace afam;

namespace {

const Index3 kDims{23, 19, 17};

/// 0 in a slanted slab and a ball: shapes that cross planes and rows.
std::vector<uint8_t> mask() {
  std::vector<uint8_t> m(size_t(kDims[0] * kDims[1] * kDims[2]), 1);
  size_t i = 0;
  for (int64_t z = 0; z < kDims[2]; ++z)
    for (int64_t y = 0; y < kDims[1]; ++y)
      for (int64_t x = 0; x < kDims[0]; ++x, ++i) {
        const int64_t dx = x - 15, dy = y - 6, dz = z - 9;
        if (x + y < z || dx * dx + dy * dy + dz * dz < 20) m[i] = 0;
      }
  return m;
}

}  // namespace

TEST(ValidMaskSource, ReadsNaNExactlyWhereTheMaskIsZero) {
  const std::vector<float> v = afam_test::movingBlob(kDims, 0);
  const std::vector<uint8_t> valid = mask();
  ArraySource inner(v.data(), kDims);
  ValidMaskSource source(inner, valid.data());
  std::vector<float> planes(v.size());
  source.readSlab(0, kDims[2], planes.data());
  const int64_t y0 = 5, rows = 7, z0 = 3, zCount = 9;
  std::vector<float> some(size_t(kDims[0] * rows * zCount));
  source.readRows(z0, zCount, y0, rows, some.data());
  int64_t missing = 0;
  for (size_t i = 0; i < v.size(); ++i) {
    missing += valid[i] == 0 ? 1 : 0;
    ASSERT_EQ(std::isnan(planes[i]), valid[i] == 0) << "sample " << i;
    if (valid[i] != 0) {
      ASSERT_EQ(planes[i], v[i]);
    }
  }
  EXPECT_GT(missing, 100);
  size_t q = 0;
  for (int64_t z = z0; z < z0 + zCount; ++z)
    for (int64_t y = y0; y < y0 + rows; ++y)
      for (int64_t x = 0; x < kDims[0]; ++x, ++q) {
        const size_t i = size_t((z * kDims[1] + y) * kDims[0] + x);
        ASSERT_EQ(std::isnan(some[q]), valid[i] == 0) << "x " << x << " y " << y << " z " << z;
      }
}

TEST(ValidMaskSource, EncodesAsTheSameVolumeWithNaNAtTheMask) {
  const std::vector<float> v = afam_test::movingBlob(kDims, 0);
  const std::vector<uint8_t> valid = mask();
  std::vector<float> holes = v;
  for (size_t i = 0; i < v.size(); ++i)
    if (valid[i] == 0) holes[i] = std::nanf("");
  EncoderOptions o;
  o.levels = 2;
  o.blocksPerAxis = 3;
  o.errorBound = 1e-2;
  o.threads = 2;
  ArraySource inner(v.data(), kDims);
  ValidMaskSource masked(inner, valid.data());
  ArraySource nan(holes.data(), kDims);
  const std::string a = afam_test::scratchPath("valid_mask.afam"),
                    b = afam_test::scratchPath("nan_holes.afam");
  encodeVolume(masked, o, a);
  encodeVolume(nan, o, b);
  const std::vector<char> bytes = afam_test::readAll(a);
  EXPECT_GT(bytes.size(), 100u);
  EXPECT_EQ(bytes, afam_test::readAll(b));
}
