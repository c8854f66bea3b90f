// SPDX-License-Identifier: BSD-3-Clause
// What the fuzz targets of Testing/Fuzz found, one test per finding: the input, and the error it
// must now give.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "afam/base/errors.hpp"
#include "afam/encode/encoder.hpp"
#include "scratch_dir.hpp"

using namespace afam;

TEST(FuzzFindings, RawNameWithAZeroDimensionIsNotAVolumeName) {
  // fuzz_raw_file, input "...c_0x3x4_int16.raw": parseRawName said yes with dims 0x3x4.
  Index3 dims{};
  SampleType type{};
  EXPECT_FALSE(parseRawName("a/b/c_0x3x4_int16.raw", dims, type));
  EXPECT_FALSE(parseRawName("c_3x0x4_int16.raw", dims, type));
  EXPECT_TRUE(parseRawName("c_2x3x4_int16.raw", dims, type));
  EXPECT_EQ(dims, (Index3{2, 3, 4}));
}

TEST(FuzzFindings, RawNameWithAHugeDimensionIsNotAVolumeNameAndThrowsNothing) {
  // Twenty digits made std::stoll throw std::out_of_range (the CLI printed "stoll").
  Index3 dims{};
  SampleType type{};
  EXPECT_NO_THROW(EXPECT_FALSE(parseRawName("v_99999999999999999999x1x1_uint8.raw", dims, type)));
  EXPECT_FALSE(parseRawName("v_2147483648x1x1_uint8.raw", dims, type));  // above 2^31 - 1
  EXPECT_TRUE(parseRawName("v_2147483647x1x1_uint8.raw", dims, type));
}

TEST(FuzzFindings, RawSizeThatOverflowsIsRefusedNotMatchedByAnEmptyFile) {
  // 2^30 x 2^30 x 16 uint8 is 2^64 bytes, which wrapped to 0: an empty file passed the size check.
  const std::string path = afam_test::scratchPath("empty_1073741824x1073741824x16_uint8.raw");
  std::ofstream(path).close();
  try {
    RawFileSource source(path, {1073741824, 1073741824, 16}, SampleType::UInt8);
    FAIL() << "an empty file was accepted as a 2^64-byte volume";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("more than 2^64 bytes"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}
