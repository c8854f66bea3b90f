// SPDX-License-Identifier: BSD-3-Clause
// What a file promises, checked as a reader sees it: every block of every level within the
// file's bound (RMSE or pointwise) against the samples it stands for, decoded by
// AfamFile::readPayload (the function `afam verify` and the renderer read through), and the
// compact form a cache keeps giving the same floats bit for bit.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "afam/format/afam_file.hpp"
#include "afam/format/block_decode.hpp"
#include "afam/format/compact_form.hpp"
#include "afam/sampling/block_sampling.hpp"

namespace afam_test {

/// Every block of every level of `f` within the file's bound against the samples it stands for,
/// as the reader decodes it; the compact form equal to the floats.
inline void expectEveryBlockWithinItsBound(const afam::AfamFile& f, afam::VolumeSource& src) {
  using namespace afam;
  const double bound = absoluteBound(f.header());
  const bool pointwise = f.header().boundKind == BoundKind::MaxError;
  const Partition& part = f.partition();
  BlockRowReader reader(src, part);
  std::vector<std::vector<float>> raw;
  std::vector<float> payload, decoded, compact, expanded;
  for (int level = 0; level < part.levels(); ++level) {
    const Int3 nb = part.blocksPerAxis(level);
    for (int kz = 0; kz < nb[2]; ++kz) {
      reader.readRow(level, kz, false, f.header().sampling, raw);
      for (int j = 0; j < nb[1]; ++j)
        for (int i = 0; i < nb[0]; ++i) {
          const int64_t e = f.entryIndex(level, {i, j, kz});
          const ModelEntry& m = f.entries()[size_t(e)];
          const std::string where = Partition::blockName(level, {i, j, kz});
          payload.assign(m.size / sizeof(float), 0.0f);
          f.readPayload(e, payload.data());
          decodeBlockSamples(m, payload.data(), f.header().mode, decoded);
          const std::vector<float>& s = raw[size_t(j * nb[0] + i)];
          ASSERT_EQ(decoded.size(), s.size()) << where;
          double squares = 0, worst = 0, largest = 0;
          int64_t valid = 0;
          for (size_t k = 0; k < s.size(); ++k) {
            if (std::isnan(s[k])) continue;
            largest = std::max(largest, std::fabs(double(s[k])));
            const double d = double(decoded[k]) - double(s[k]);
            squares += d * d;
            worst = std::max(worst, std::fabs(d));
            ++valid;
          }
          const double rmse = valid ? std::sqrt(squares / double(valid)) : 0.0;
          // The index records the error of what a reader decodes (the encoder measured it so, in
          // double; the decoded floats differ by their rounding, a few float ulps of the values).
          EXPECT_NEAR(double(pointwise ? m.maxError : m.rmse), pointwise ? worst : rmse,
                      1e-4 * bound + 1e-6 * (pointwise ? worst : rmse) + 1e-6 * largest)
              << where << ": the index's error is not the decoded model's";
          EXPECT_LE(pointwise ? worst : rmse, bound)
              << where << " (" << blockKindName(m.kind) << ", rounded points " << m.roundedPoints
              << ") as the reader decodes it";
          const CompactForm form = f.readCompact(e, 1.0, compact);
          if (form.width == 0) continue;
          expanded.resize(size_t(controlCount(m)));
          expandCompact(compact.data(), form, expanded.size(), expanded.data());
          for (size_t k = 0; k < expanded.size(); ++k)
            ASSERT_EQ(expanded[k], payload[k]) << where << " point " << k << " in compact form";
        }
    }
  }
}

}  // namespace afam_test
