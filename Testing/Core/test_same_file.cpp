// SPDX-License-Identifier: BSD-3-Clause
// The ranks' check that they draw one file (ranks/same_file.hpp).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "afam/ranks/same_file.hpp"
#include "skewed_blob.hpp"

using afam::AfamFile;
using afam::contentFingerprint;
using afam::ranksFileDisagreement;

TEST(SameFile, OneFileOnEveryHandleAnotherEncodeDiffers) {
  const auto a = afam_test::encodeSkewedBlob();
  const auto b = AfamFile::open(a->path());  // another rank's handle of the same file
  EXPECT_NE(contentFingerprint(*a), 0u);
  EXPECT_EQ(contentFingerprint(*a), contentFingerprint(*b));
  const auto coarser = afam_test::encodeSkewedBlob(1e-2, "same_file_coarser.afam");
  EXPECT_NE(contentFingerprint(*a), contentFingerprint(*coarser));
}

TEST(SameFile, TheVerdictNamesTheRanksAndThePath) {
  const std::string path = "/data/scan.afam";
  EXPECT_EQ(ranksFileDisagreement({7, 7, 7, 7}, path), "");
  EXPECT_EQ(ranksFileDisagreement({7}, path), "");
  EXPECT_EQ(ranksFileDisagreement({7, 0, 7}, path),
            "the 3 ranks do not draw one file: rank 1 could not open /data/scan.afam (each node "
            "must see the same file); the volume is not drawn");
  EXPECT_EQ(ranksFileDisagreement({7, 9, 0, 9, 0}, path),
            "the 5 ranks do not draw one file: ranks 2 and 4 could not open /data/scan.afam; "
            "ranks 1 and 3 opened another /data/scan.afam than rank 0 did (each node must see "
            "the same file); the volume is not drawn");
  EXPECT_EQ(ranksFileDisagreement({0, 5, 6, 5}, path),
            "the 4 ranks do not draw one file: rank 0 could not open /data/scan.afam; rank 2 "
            "opened another /data/scan.afam than rank 1 did (each node must see the same file); "
            "the volume is not drawn");
  EXPECT_EQ(ranksFileDisagreement({0, 0}, path),
            "the 2 ranks do not draw one file: ranks 0 and 1 could not open /data/scan.afam (each "
            "node must see the same file); the volume is not drawn");
}
