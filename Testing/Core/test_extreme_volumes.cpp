// SPDX-License-Identifier: BSD-3-Clause
// Stiff and extreme volumes, generated: every encode meets its RMSE bound on every level (measured
// on the decoded level against the samples it stands for, as `afam verify --against` does), or
// refuses with a message; coarse levels approximate the filtered volume instead of aliasing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "afam/encode/encoder.hpp"
#include "afam/format/block_decode.hpp"

using namespace afam;

namespace {

struct Volume {
  std::string name;
  Index3 dims;
  std::vector<float> v;
};

Volume make(const std::string& name, Index3 d,
            const std::function<double(int64_t, int64_t, int64_t)>& f) {
  Volume vol{name, d, std::vector<float>(size_t(d[0] * d[1] * d[2]))};
  size_t i = 0;
  for (int64_t z = 0; z < d[2]; ++z)
    for (int64_t y = 0; y < d[1]; ++y)
      for (int64_t x = 0; x < d[0]; ++x) vol.v[i++] = static_cast<float>(f(x, y, z));
  return vol;
}

double smooth(int64_t x, int64_t y, int64_t z) {
  return std::sin(0.31 * double(x)) * std::cos(0.23 * double(y + z));
}

std::vector<Volume> extremeVolumes() {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Volume> all;
  all.push_back(make("constant", {20, 20, 20}, [](int64_t, int64_t, int64_t) { return 3.25; }));
  all.push_back(make("spike", {33, 33, 33}, [](int64_t x, int64_t y, int64_t z) {
    return x == 16 && y == 17 && z == 15 ? 1000.0 : 0.0;
  }));
  all.push_back(
      make("step", {30, 30, 30}, [](int64_t x, int64_t, int64_t) { return x < 13 ? -1.0 : 2.0; }));
  all.push_back(make("checkerboard", {24, 24, 24},
                     [](int64_t x, int64_t y, int64_t z) { return double((x + y + z) % 2); }));
  all.push_back(make("noise", {40, 40, 40}, [&](int64_t, int64_t, int64_t) { return u(rng); }));
  all.push_back(make("odd_sizes", {17, 23, 11}, smooth));
  all.push_back(make("two_cubed", {2, 2, 2},
                     [](int64_t x, int64_t y, int64_t z) { return double(x + 2 * y + 4 * z); }));
  all.push_back(make("two_sample_axis", {30, 30, 2}, smooth));
  all.push_back(make("needle", {300, 3, 3}, [](int64_t x, int64_t y, int64_t z) {
    return smooth(x, y, z) + 0.1 * double(y * z);
  }));
  all.push_back(make("fifty_decades", {24, 24, 24}, [](int64_t x, int64_t y, int64_t z) {
    return std::pow(10.0, -25.0 + 50.0 * double(x + y + z) / 69.0);
  }));
  all.push_back(make("subnormal", {24, 24, 24},
                     [](int64_t x, int64_t y, int64_t z) { return 1e-40 * smooth(x, y, z); }));
  all.push_back(make("large_offset", {40, 40, 40},
                     [](int64_t x, int64_t y, int64_t z) { return 1e7 + smooth(x, y, z); }));
  all.push_back(make("plateaus", {36, 36, 36}, [](int64_t x, int64_t y, int64_t z) {
    return std::floor(4 * smooth(x, y, z));
  }));
  return all;
}

/// RMSE of one decoded level against the samples it stands for (the level's own sampling rule).
double levelRmse(const InMemoryModels& m, VolumeSource& src, int level) {
  BlockRowReader reader(src, m.partition);
  std::vector<std::vector<float>> raw;
  std::vector<float> decoded;
  double sum = 0;
  int64_t count = 0;
  const Int3 nb = m.partition.blocksPerAxis(level);
  for (int kz = 0; kz < nb[2]; ++kz) {
    reader.readRow(level, kz, false, m.header.sampling, raw);
    for (int j = 0; j < nb[1]; ++j)
      for (int i = 0; i < nb[0]; ++i) {
        const int64_t e = m.entryIndex(level, {i, j, kz});
        decodeBlockSamples(m.entries[size_t(e)], m.payloads[size_t(e)].data(), m.header.mode,
                           decoded);
        const std::vector<float>& s = raw[size_t(j * nb[0] + i)];
        for (size_t k = 0; k < s.size(); ++k) {
          const double d = double(decoded[k]) - double(s[k]);
          sum += d * d;
        }
        count += int64_t(s.size());
      }
  }
  return std::sqrt(sum / double(count));
}

EncoderOptions relativeOptions(double bound, int levels, int blocks) {
  EncoderOptions opt;
  opt.errorBound = bound;
  opt.relativeBound = true;
  opt.levels = levels;
  opt.blocksPerAxis = blocks;
  opt.threads = 2;
  return opt;
}

struct Case {
  double bound;
  int levels, blocks;
};

}  // namespace

TEST(ExtremeVolumes, EveryLevelMeetsItsBound) {
  // levels/blocks 0: the default partition from the dimensions.
  const Case cases[] = {{1e-2, 0, 0},  {1e-3, 0, 0}, {1e-4, 0, 0}, {1e-2, 4, 16}, {1e-3, 4, 16},
                        {1e-4, 4, 16}, {1e-2, 2, 4}, {1e-3, 2, 4}, {1e-4, 2, 4}};
  for (const Volume& vol : extremeVolumes()) {
    for (const Case& c : cases) {
      SCOPED_TRACE(vol.name + " bound " + std::to_string(c.bound) + " levels " +
                   std::to_string(c.levels) + " blocks " + std::to_string(c.blocks));
      ArraySource src(vol.v.data(), vol.dims);
      const EncoderOptions opt = relativeOptions(c.bound, c.levels, c.blocks);
      InMemoryModels m;
      EncodeStats st;
      const int64_t longest = std::max({vol.dims[0], vol.dims[1], vol.dims[2]});
      if (c.blocks > std::max<int64_t>(1, longest - 1)) {  // no axis holds them: refused
        EXPECT_THROW(encodeVolume(src, opt, m), InvalidArgument);
        continue;
      }
      ASSERT_NO_THROW(st = encodeVolume(src, opt, m));
      const double absBound = c.bound * (st.valueMax - st.valueMin);
      EXPECT_DOUBLE_EQ(st.bound, absBound);
      EXPECT_LE(st.maxRmse, absBound);
      for (int l = 0; l < m.partition.levels(); ++l) {
        EXPECT_LE(st.levels[size_t(l)].maxRmse, absBound) << "level " << l;
        EXPECT_LE(levelRmse(m, src, l), absBound) << "decoded level " << l;
      }
    }
  }
}

TEST(ExtremeVolumes, NoiseUnderFlatCoarseLevelsIsSearched) {
  // White noise: a coarse level is the box-filtered noise, nearly flat (the fewest points meet the
  // bound), a finer one is not: each block's search asks its own samples, never its parent's
  // verdict (the paper's cross-level reuse), and every level keeps the bound.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  const Volume vol = make("noise", {48, 48, 48}, [&](int64_t, int64_t, int64_t) { return u(rng); });
  ArraySource src(vol.v.data(), vol.dims);
  EncoderOptions opt = relativeOptions(0.05, 3, 2);
  opt.compact = false;  // float splines: their NCP says what each level needed
  InMemoryModels m;
  const EncodeStats st = encodeVolume(src, opt, m);
  const Partition& part = m.partition;
  const auto most = [](const Int3& v) { return std::max({v[0], v[1], v[2]}); };
  const auto fewest = [&](const ModelEntry& e) {
    return e.kind == BlockKind::Constant ||
           most(e.ncp) <= std::min(opt.degree + 1, most(e.samples));
  };
  int64_t underFlat = 0;  // blocks of more points under a parent of the fewest
  for (int l = 1; l < part.levels(); ++l)
    for (int64_t li = 0; li < part.blockCount(l); ++li) {
      const Int3 ijk = part.blockFromLinear(l, li);
      const ModelEntry& e = m.entries[size_t(m.entryIndex(l, ijk))];
      const ModelEntry& p = m.entries[size_t(m.entryIndex(l - 1, part.parent(l, ijk)))];
      underFlat += fewest(p) && !fewest(e) ? 1 : 0;
    }
  for (const LevelStats& ls : st.levels) EXPECT_EQ(ls.searched, ls.blocks);
  EXPECT_GT(underFlat, 0) << "noise under flat coarse blocks needs more than the fewest points";
  EXPECT_LE(st.maxRmse, st.bound);
  for (int l = 0; l < part.levels(); ++l) EXPECT_LE(levelRmse(m, src, l), st.bound) << l;
}

TEST(ExtremeVolumes, CoarsestCheckerboardLevelIsItsMean) {
  const Volume vol = make("checkerboard", {24, 24, 24},
                          [](int64_t x, int64_t y, int64_t z) { return double((x + y + z) % 2); });
  ArraySource src(vol.v.data(), vol.dims);
  InMemoryModels m;
  encodeVolume(src, relativeOptions(1e-3, 3, 4), m);
  std::vector<float> decoded;
  double sum = 0;
  int64_t count = 0;
  for (int64_t e = m.levelStart[0]; e < m.levelStart[1]; ++e) {
    decodeBlockSamples(m.entries[size_t(e)], m.payloads[size_t(e)].data(), m.header.mode, decoded);
    for (float v : decoded) sum += std::fabs(double(v) - 0.5);
    count += int64_t(decoded.size());
  }
  EXPECT_LE(sum / double(count), 0.02) << "a moire of 0s and 1s would give about 0.5";
  // The finest level still holds the checkerboard itself.
  EXPECT_LE(levelRmse(m, src, 2), 1e-3);
}

TEST(ExtremeVolumes, InfiniteSamplesAreRefusedByName) {  // NaN marks a missing sample
  for (const float bad :
       {std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity()}) {
    Volume vol = make("nan", {12, 12, 12}, smooth);
    vol.v[size_t((5 * 12 + 4) * 12 + 3)] = bad;
    ArraySource src(vol.v.data(), vol.dims);
    EncoderOptions opt;
    opt.errorBound = 1e-3;
    opt.relativeBound = true;
    InMemoryModels m;
    try {
      encodeVolume(src, opt, m);
      ADD_FAILURE() << "non-finite sample accepted";
    } catch (const NumericError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("sample (3, 4, 5)"), std::string::npos) << msg;
      EXPECT_NE(msg.find(bad > 0 ? "+Inf" : "-Inf"), std::string::npos) << msg;
    }
  }
}

TEST(ExtremeVolumes, BadBoundsAndPartitionsSayWhatToChange) {
  const Volume vol = make("smooth", {12, 12, 12}, smooth);
  ArraySource src(vol.v.data(), vol.dims);
  auto message = [&](EncoderOptions opt) {
    InMemoryModels m;
    try {
      encodeVolume(src, opt, m);
    } catch (const InvalidArgument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EncoderOptions opt;
  opt.errorBound = 0;
  EXPECT_NE(message(opt).find("--error-bound"), std::string::npos) << message(opt);
  opt.errorBound = -1;
  EXPECT_NE(message(opt).find("must be finite and > 0"), std::string::npos) << message(opt);
  opt.errorBound = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(message(opt).find("must be finite"), std::string::npos) << message(opt);
  opt.errorBound = 1e-3;
  opt.levels = 40;
  EXPECT_NE(message(opt).find("levels"), std::string::npos) << message(opt);
  opt.levels = 2;
  opt.blocksPerAxis = -1;
  EXPECT_NE(message(opt).find("blocks"), std::string::npos) << message(opt);
}
