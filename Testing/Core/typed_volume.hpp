// SPDX-License-Identifier: BSD-3-Clause
// A volume stored as 1- or 2-byte integers or float32 (the types a LevelSampler holds), from the
// Marschner-Lobb field with noise, and its load into a level sampler (level_sampler.hpp).
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "afam/format/partition.hpp"
#include "afam/sampling/level_sampler.hpp"
#include "afam/volume/marschner_lobb.hpp"

namespace afam_test {

using afam::Index3;
using afam::SampleType;

/// A volume of `type` from the Marschner-Lobb field (noise added, so that coarse blocks differ
/// from any smooth interpolant), as stored and as floats.
struct TypedVolume {
  Index3 dims;
  SampleType type;
  std::vector<unsigned char> bytes;
  std::vector<float> floats;
};

inline TypedVolume typedVolume(Index3 dims, SampleType type) {
  TypedVolume t{dims, type, {}, {}};
  const size_t n = size_t(dims[0] * dims[1] * dims[2]);
  std::vector<float> ml(n);
  afam::marschnerLobbSlab(afam::MarschnerLobb{}, dims, 0, dims[2], ml.data());
  t.floats.resize(n);
  t.bytes.resize(n * size_t(afam::sampleTypeSize(type)));
  uint32_t state = 12345;
  for (size_t i = 0; i < n; ++i) {
    state = state * 1664525u + 1013904223u;
    const double noise = double(state >> 8) / double(1u << 24) - 0.5;
    const double v = ml[i] + 0.05 * noise;
    if (type == SampleType::UInt8) {
      const auto b = uint8_t(std::lround(std::fmin(std::fmax(200 * v + 20, 0), 255)));
      t.bytes[i] = b;
      t.floats[i] = b;
    } else if (type == SampleType::Int16) {
      const auto w = int16_t(std::lround(30000 * v - 12000));
      std::memcpy(t.bytes.data() + 2 * i, &w, 2);
      t.floats[i] = w;
    } else {
      const auto f = float(1e3 * v - 250.0);
      std::memcpy(t.bytes.data() + 4 * i, &f, 4);
      t.floats[i] = f;
    }
  }
  return t;
}

/// Loads the volume into a sampler in three pieces of planes.
inline void loadAll(afam::LevelSampler& s, const TypedVolume& t) {
  std::string why;
  ASSERT_TRUE(s.reserve(t.dims, t.type, why)) << why;
  const size_t plane = size_t(t.dims[0] * t.dims[1]) * size_t(afam::sampleTypeSize(t.type));
  const int64_t cuts[] = {0, 5, t.dims[2] / 2, t.dims[2]};
  for (int c = 0; c < 3; ++c)
    s.load(cuts[c], cuts[c + 1] - cuts[c], t.bytes.data() + size_t(cuts[c]) * plane);
}

/// Every z-row of every level of `part`, box- and point-sampled, with and without ghosts, from `s`
/// (t loaded) against sampleBlockRow's from t itself, bit for bit; the samples compared.
inline size_t compareRowsWithTheSampling(afam::LevelSampler& s, const TypedVolume& t,
                                         const afam::Partition& part) {
  using namespace afam;
  ArraySource src(t.bytes.data(), t.type, t.dims);
  PlaneReader planes(src, t.dims);
  size_t compared = 0;
  for (const LevelSampling sampling : {LevelSampling::Box, LevelSampling::Point})
    for (const bool ghost : {false, true})
      for (int l = 0; l < part.levels(); ++l) {
        const Int3 nb = part.blocksPerAxis(l);
        for (int kz = 0; kz < nb[2]; ++kz) {
          SCOPED_TRACE(testing::Message()
                       << sampleTypeName(t.type) << " level " << l << " row " << kz << " box "
                       << (sampling == LevelSampling::Box) << " ghost " << ghost);
          std::vector<Int3> row;
          for (int j = 0; j < nb[1]; ++j)
            for (int i = 0; i < nb[0]; ++i) row.push_back({i, j, kz});
          std::vector<std::vector<float>> want(row.size()), got(row.size());
          std::vector<std::vector<float>*> w, g;
          for (size_t b = 0; b < row.size(); ++b) {
            w.push_back(&want[b]);
            g.push_back(&got[b]);
          }
          sampleBlockRow(part, planes, l, row, ghost, sampling, w);
          s.sampleRow(part, l, row, ghost, sampling, g);
          for (size_t b = 0; b < row.size(); ++b) {
            if (got[b].size() != want[b].size() ||
                std::memcmp(got[b].data(), want[b].data(), want[b].size() * 4) != 0) {
              ADD_FAILURE() << "block " << b << ": " << got[b].size() << " samples, "
                            << want[b].size() << " sampled, or other floats";
              return compared;
            }
            compared += want[b].size();
          }
        }
      }
  return compared;
}

}  // namespace afam_test
