// SPDX-License-Identifier: BSD-3-Clause
// Test helper: the repository's head MRI (Testing/Data/volumes), for tests that make a real scan
// large (EnlargedScanSource).
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace afam_test {

/// The repository's head MRI (48 x 62 x 42 uint8) as floats, x fastest.
inline std::vector<float> headMri() {
  std::ifstream in(std::string(AFAM_TEST_DATA_DIR) + "/volumes/HeadMRVolume_48x62x42_uint8.raw",
                   std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(bytes.size(), size_t(48 * 62 * 42));
  std::vector<float> v(bytes.size());
  for (size_t i = 0; i < v.size(); ++i) v[i] = float(uint8_t(bytes[i]));
  return v;
}

}  // namespace afam_test
