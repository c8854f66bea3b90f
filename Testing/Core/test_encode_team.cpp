// SPDX-License-Identifier: BSD-3-Clause
// Encoding by a team of processes (threads standing in for MPI ranks): the same models, byte for
// byte, as one process; members without rows; an error on one member reaches all of them.
#include <gtest/gtest.h>

#include <cmath>
#include <exception>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "afam/encode/encoder.hpp"
#include "afam/volume/marschner_lobb.hpp"
#include "thread_team.hpp"

using namespace afam;

namespace {

std::vector<float> mlVolume(Index3 dims) {
  std::vector<float> v(size_t(dims[0] * dims[1] * dims[2]));
  marschnerLobbSlab(MarschnerLobb{}, dims, 0, dims[2], v.data());
  return v;
}

EncoderOptions relativeBound(int levels, int blocks, double bound) {
  EncoderOptions opt;
  opt.levels = levels;
  opt.blocksPerAxis = blocks;
  opt.errorBound = bound;
  opt.relativeBound = true;
  return opt;
}

/// Models in memory, or an I/O error when the file would be started (e.g. a full disk on rank 0).
struct MemberSink : InMemoryModels {
  bool fails = false;
  void begin(const VolumeHeader& h) override {
    if (fails) throw IoError("cannot create the temporary file (test)");
    InMemoryModels::begin(h);
  }
};

struct MemberResult {
  MemberSink models;
  EncodeStats stats;
  std::string error;
  bool numericError = false;
};

/// Encodes v with `members` threads as a team; member r's sink and statistics in result[r].
std::vector<MemberResult> encodeAsTeam(const std::vector<float>& v, Index3 dims, EncoderOptions opt,
                                       int members, bool firstSinkFails = false) {
  afam_test::ThreadTeamHub hub(members);
  std::vector<MemberResult> result(static_cast<size_t>(members));
  std::vector<std::thread> threads;
  opt.threads = 1;
  for (int r = 0; r < members; ++r)
    threads.emplace_back([&, r] {
      afam_test::ThreadTeam team(hub, r);
      ArraySource source(v.data(), dims, "ml");
      MemberResult& out = result[size_t(r)];
      out.models.fails = firstSinkFails && r == 0;
      try {
        out.stats = encodeVolume(source, opt, out.models, team);
      } catch (const NumericError& e) {
        out.error = e.what();
        out.numericError = true;
      } catch (const std::exception& e) {
        out.error = e.what();
      }
    });
  for (std::thread& t : threads) t.join();
  return result;
}

InMemoryModels encodeAlone(const std::vector<float>& v, Index3 dims, EncoderOptions opt,
                           EncodeStats& stats) {
  ArraySource source(v.data(), dims, "ml");
  InMemoryModels models;
  opt.threads = 2;
  stats = encodeVolume(source, opt, models);
  return models;
}

/// Model by model: block, kind, NCP per axis, degree, value range, RMSE and the stored bytes.
void expectSameModels(const InMemoryModels& a, const InMemoryModels& b) {
  ASSERT_EQ(a.entries.size(), b.entries.size());
  EXPECT_EQ(a.header.valueMin, b.header.valueMin);
  EXPECT_EQ(a.header.valueMax, b.header.valueMax);
  for (size_t i = 0; i < a.entries.size(); ++i) {
    const ModelEntry &x = a.entries[i], &y = b.entries[i];
    SCOPED_TRACE("model " + std::to_string(i));
    EXPECT_EQ(x.level, y.level);
    EXPECT_EQ(x.block, y.block);
    EXPECT_EQ(x.ncp, y.ncp);
    EXPECT_EQ(x.degree, y.degree);
    EXPECT_EQ(int(x.kind), int(y.kind));
    EXPECT_EQ(x.rmse, y.rmse);
    EXPECT_EQ(x.checksum, y.checksum);
    EXPECT_EQ(a.stored[i], b.stored[i]);
  }
}

TEST(EncodeTeam, SharesAreContiguousAndCoverEveryLine) {
  for (int64_t lines : {1, 2, 5, 16, 37})
    for (int size : {1, 2, 3, 7, 64}) {
      int64_t next = 0;
      for (int r = 0; r < size; ++r) {
        const WorkShare s = workShare(lines, r, size);
        if (s.empty()) continue;
        EXPECT_EQ(s.first, next) << lines << " lines, " << size << " members";
        EXPECT_LE(s.end - s.first, (lines + size - 1) / size);
        next = s.end;
      }
      EXPECT_EQ(next, lines) << lines << " lines, " << size << " members";
    }
  EXPECT_TRUE(workShare(2, 5, 7).empty());
}

TEST(EncodeTeam, ThreeMembersGiveTheModelsOfOneProcess) {
  const Index3 dims{41, 37, 45};  // awkward sizes: rows of unequal sample counts
  std::vector<float> v = mlVolume(dims);
  for (size_t i = 0; i < v.size(); ++i)
    if (i % 41 < 20) v[i] = 0.25f;  // a flat half: constant blocks beside searched ones
  const EncoderOptions opt = relativeBound(3, 5, 2e-3);
  EncodeStats alone;
  const InMemoryModels want = encodeAlone(v, dims, opt, alone);
  const std::vector<MemberResult> team = encodeAsTeam(v, dims, opt, 3);
  for (const MemberResult& m : team) ASSERT_EQ(m.error, "");
  expectSameModels(team[0].models, want);
  EXPECT_EQ(team[0].stats.blocks, alone.blocks);
  EXPECT_EQ(team[0].stats.payloadBytes, alone.payloadBytes);
  EXPECT_EQ(team[0].stats.fits, alone.fits);
  EXPECT_EQ(team[0].stats.maxRmse, alone.maxRmse);
  for (size_t l = 0; l < alone.levels.size(); ++l) {
    EXPECT_EQ(team[0].stats.levels[l].searched, alone.levels[l].searched) << "level " << l;
    EXPECT_EQ(team[0].stats.levels[l].complex, alone.levels[l].complex) << "level " << l;
    EXPECT_EQ(team[0].stats.levels[l].payloadBytes, alone.levels[l].payloadBytes) << "level " << l;
  }
  EXPECT_GT(alone.levels[2].complex, 0);
  EXPECT_LT(alone.levels[2].complex, alone.levels[2].blocks);
  EXPECT_TRUE(team[1].models.entries.empty() || team[1].models.entries[0].storedSize == 0);
}

TEST(EncodeTeam, MoreMembersThanRowsAndOtherModes) {
  const Index3 dims{20, 24, 18};
  const std::vector<float> v = mlVolume(dims);
  for (EncodingMode mode :
       {EncodingMode::Adaptive, EncodingMode::InLevel, EncodingMode::Downsampled}) {
    EncoderOptions opt;
    opt.levels = 2;
    opt.blocksPerAxis = 2;  // one row at level 0, two at level 1: 5 members have nothing to fit
    opt.errorBound = 1e-3;
    opt.mode = mode;
    EncodeStats alone;
    const InMemoryModels want = encodeAlone(v, dims, opt, alone);
    const std::vector<MemberResult> team = encodeAsTeam(v, dims, opt, 7);
    for (const MemberResult& m : team) ASSERT_EQ(m.error, "");
    expectSameModels(team[0].models, want);
  }
}

/// A source that may only be read on the thread that made it (an MPI without thread support).
class CallingThreadSource : public ArraySource {
 public:
  using ArraySource::ArraySource;
  bool readsOnCallingThread() const override { return true; }
  void readSlab(int64_t z0, int64_t zCount, float* out) override {
    if (std::this_thread::get_id() != owner_) ++readsElsewhere;
    ArraySource::readSlab(z0, zCount, out);
  }
  int readsElsewhere = 0;

 private:
  std::thread::id owner_ = std::this_thread::get_id();
};

TEST(EncodeTeam, ASourceReadOnTheCallingThreadOnlyGivesTheSameModels) {
  const Index3 dims{30, 26, 34};
  const std::vector<float> v = mlVolume(dims);
  EncoderOptions opt = relativeBound(3, 4, 1e-3);
  EncodeStats alone;
  const InMemoryModels want = encodeAlone(v, dims, opt, alone);
  CallingThreadSource source(v.data(), dims, "ml");
  InMemoryModels got;
  opt.threads = 2;
  encodeVolume(source, opt, got);
  EXPECT_EQ(source.readsElsewhere, 0);
  expectSameModels(got, want);
}

TEST(EncodeTeam, AnErrorOnOneMemberReachesEveryMember) {
  const Index3 dims{16, 16, 30};
  std::vector<float> v = mlVolume(dims);
  v[size_t((25 * 16 + 3) * 16 + 5)] =
      std::numeric_limits<float>::infinity();  // plane 25: member 2 of 3 scans it (NaN: missing)
  EncoderOptions opt;
  opt.levels = 2;
  opt.blocksPerAxis = 2;
  const std::vector<MemberResult> team = encodeAsTeam(v, dims, opt, 3);
  EXPECT_TRUE(team[2].numericError) << team[2].error;
  EXPECT_NE(team[2].error.find("sample (5, 3, 25)"), std::string::npos) << team[2].error;
  for (int r : {0, 1}) {
    EXPECT_FALSE(team[size_t(r)].numericError);
    EXPECT_NE(team[size_t(r)].error.find("rank 2: "), std::string::npos) << team[size_t(r)].error;
    EXPECT_NE(team[size_t(r)].error.find("is +Inf"), std::string::npos) << team[size_t(r)].error;
    EXPECT_TRUE(team[size_t(r)].models.entries.empty());
  }
}

TEST(EncodeTeam, TheFirstMembersSinkFailingStopsEveryMember) {
  const Index3 dims{16, 16, 20};
  const std::vector<float> v = mlVolume(dims);
  const std::vector<MemberResult> team = encodeAsTeam(v, dims, relativeBound(2, 2, 1e-3), 3, true);
  EXPECT_NE(team[0].error.find("cannot create the temporary file"), std::string::npos)
      << team[0].error;
  for (int r : {1, 2})
    EXPECT_NE(team[size_t(r)].error.find("rank 0: cannot create the temporary file"),
              std::string::npos)
        << team[size_t(r)].error;
}

}  // namespace
