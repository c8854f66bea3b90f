// SPDX-License-Identifier: BSD-3-Clause
// An EncodeTeam whose processes are threads of the test (no MPI): each collective is a deposit of
// every member's part, a barrier, a read of all parts, and a second barrier before parts are
// reused.
#pragma once

#include <algorithm>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "afam/encode/encode_team.hpp"

namespace afam_test {

/// What the members of one team share.
class ThreadTeamHub {
 public:
  explicit ThreadTeamHub(int members)
      : bytes_(size_t(members)),
        ranges_(size_t(members)),
        errors_(size_t(members)),
        size_(members) {}
  int size() const { return size_; }
  void barrier() {
    std::unique_lock<std::mutex> lock(mutex_);
    const int64_t generation = generation_;
    if (++arrived_ == size_) {
      arrived_ = 0;
      ++generation_;
      wake_.notify_all();
      return;
    }
    wake_.wait(lock, [&] { return generation_ != generation; });
  }
  std::vector<std::vector<uint8_t>> bytes_;
  std::vector<std::pair<double, double>> ranges_;
  std::vector<std::string> errors_;

 private:
  int size_;
  std::mutex mutex_;
  std::condition_variable wake_;
  int arrived_ = 0;
  int64_t generation_ = 0;
};

class ThreadTeam : public afam::EncodeTeam {
 public:
  ThreadTeam(ThreadTeamHub& hub, int rank) : hub_(hub), rank_(rank) {}
  int rank() const override { return rank_; }
  int size() const override { return hub_.size(); }
  void reduceRange(double& lo, double& hi) override {
    hub_.ranges_[size_t(rank_)] = {lo, hi};
    hub_.barrier();
    for (const auto& r : hub_.ranges_) {
      lo = std::min(lo, r.first);
      hi = std::max(hi, r.second);
    }
    hub_.barrier();
  }
  void mergeFlags(std::vector<uint8_t>& flags) override {
    hub_.bytes_[size_t(rank_)] = flags;
    hub_.barrier();
    for (const auto& other : hub_.bytes_)
      for (size_t i = 0; i < flags.size(); ++i) flags[i] = std::max(flags[i], other.at(i));
    hub_.barrier();
  }
  std::vector<std::vector<uint8_t>> gatherToFirst(const std::vector<uint8_t>& bytes) override {
    hub_.bytes_[size_t(rank_)] = bytes;
    hub_.barrier();
    std::vector<std::vector<uint8_t>> all;
    if (rank_ == 0) all = hub_.bytes_;
    hub_.barrier();
    return all;
  }
  std::string agreeOnError(const std::string& localError) override {
    hub_.errors_[size_t(rank_)] = localError;
    hub_.barrier();
    std::string agreed;
    for (size_t r = 0; r < hub_.errors_.size() && agreed.empty(); ++r)
      if (!hub_.errors_[r].empty()) agreed = "rank " + std::to_string(r) + ": " + hub_.errors_[r];
    hub_.barrier();
    return agreed;
  }
  void broadcastFromFirst(std::vector<uint8_t>& bytes) override {
    if (rank_ == 0) hub_.bytes_[0] = bytes;
    hub_.barrier();
    if (rank_ != 0) bytes = hub_.bytes_[0];
    hub_.barrier();
  }

 private:
  ThreadTeamHub& hub_;
  int rank_;
};

}  // namespace afam_test
