// SPDX-License-Identifier: BSD-3-Clause
// The processes that encode one volume together (e.g. MPI ranks), as the encoder sees them.
//
// Each process fits a contiguous share (workShare) of every level's lines of blocks (the blocks
// (0..Bx-1, j, k) of one j and k, numbered k * By + j), so the blocks of one level, concatenated in
// rank order, are in the file's order; a process reads only the rows of the planes its lines need.
// The processes hand their fitted models of every level to the first process (gatherToFirst), which
// alone writes the file, level by level; a run of steps (encode_run.hpp) then shares each step's
// models with every process (broadcastFromFirst), which codes its blocks of the next step against
// them. The global value range comes from a reduction (reduceRange). Any exception on any process
// reaches every process at the next collective step (agreeOnError), so none waits for a process
// that has stopped.
//
// Every call but rank() / size() is collective: all processes call it, in the same order. Core
// knows no MPI: the ParaView filter implements this over its vtkMultiProcessController; SoloTeam
// is the one-process encode (`afam encode`), whose path through the encoder is unchanged.
#pragma once

#include <cstdint>
#include <exception>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"

namespace afam {

class EncodeTeam {
 public:
  virtual ~EncodeTeam() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  /// lo = the smallest lo over the processes, hi = the largest hi.
  virtual void reduceRange(double& lo, double& hi) = 0;
  /// Element-wise largest value over the processes (every process passes the same length).
  virtual void mergeFlags(std::vector<uint8_t>& flags) = 0;
  /// Every process's bytes, on the first process in rank order; empty on the others.
  virtual std::vector<std::vector<uint8_t>> gatherToFirst(const std::vector<uint8_t>& bytes) = 0;
  /// "" when no process failed, else "rank R: <its message>" for the lowest failing rank R, on
  /// every process. `localError` is this process's message ("" when it did not fail).
  virtual std::string agreeOnError(const std::string& localError) = 0;
  /// The first process's bytes on every process (a run's step, encode_run.hpp): `bytes` is read
  /// on the first process and replaced on the others.
  virtual void broadcastFromFirst(std::vector<uint8_t>& bytes) = 0;
};

/// One process: every collective is the identity.
class SoloTeam : public EncodeTeam {
 public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  void reduceRange(double&, double&) override {}
  void mergeFlags(std::vector<uint8_t>&) override {}
  std::vector<std::vector<uint8_t>> gatherToFirst(const std::vector<uint8_t>& bytes) override {
    return {bytes};
  }
  std::string agreeOnError(const std::string& localError) override {
    return localError.empty() ? localError : "rank 0: " + localError;
  }
  void broadcastFromFirst(std::vector<uint8_t>&) override {}
};

/// Runs one step of an encode; in a team, an exception of any process is thrown on every process
/// once all have run the step (a process's own exception as it is, another's as afam::Error naming
/// its rank), so no process waits in a later collective for one that has stopped.
template <class Step>
void teamStep(EncodeTeam& team, Step&& step) {
  if (team.size() == 1) {
    step();
    return;
  }
  std::exception_ptr failure;
  std::string message;
  try {
    step();
  } catch (const std::exception& e) {
    failure = std::current_exception();
    message = *e.what() ? e.what() : "an error with no message";
  } catch (...) {
    failure = std::current_exception();
    message = "an error that is not a std::exception";
  }
  const std::string agreed = team.agreeOnError(message);
  if (failure) std::rethrow_exception(failure);
  if (!agreed.empty()) throw Error("encode: " + agreed);
}

/// Items [first, end) of `count` (lines of blocks, z-planes) that process `rank` of `size` takes:
/// contiguous, in rank order, sizes differing by at most one (empty when rank >= count).
struct WorkShare {
  int64_t first = 0, end = 0;
  bool empty() const { return end <= first; }
};
WorkShare workShare(int64_t count, int rank, int size);

}  // namespace afam
