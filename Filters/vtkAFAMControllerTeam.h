// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkAFAMControllerTeam
 * @brief   Core's EncodeTeam over a vtkMultiProcessController (private to the module).
 *
 * The ranks of the controller encode one volume together (afam/encode/encode_team.hpp). Every call
 * runs under `Lock()`, which the piece source (vtkAFAMPieceSource) also takes around its one-sided
 * reads, so that MPI is entered by one thread at a time where MPI allows other threads than the
 * main one (MPI_THREAD_SERIALIZED or more): the encoder then samples on a thread of its own while
 * its calling thread runs these collectives. Below that level every MPI call stays on the calling
 * thread.
 */
#ifndef vtkAFAMControllerTeam_h
#define vtkAFAMControllerTeam_h

#include "afam/encode/encode_team.hpp"

#include <mutex>
#include <string>
#include <vector>

class vtkMultiProcessController;

class vtkAFAMControllerTeam : public afam::EncodeTeam
{
public:
  explicit vtkAFAMControllerTeam(vtkMultiProcessController* controller);
  int rank() const override;
  int size() const override;
  void reduceRange(double& lo, double& hi) override;
  void mergeFlags(std::vector<uint8_t>& flags) override;
  std::vector<std::vector<uint8_t>> gatherToFirst(const std::vector<uint8_t>& bytes) override;
  std::string agreeOnError(const std::string& localError) override;
  void broadcastFromFirst(std::vector<uint8_t>& bytes) override;

  /// Collective: `text` of rank `root` on every rank.
  std::string broadcast(const std::string& text, int root);
  /// Collective: the smallest `value` over the ranks.
  int reduceMin(int value);
  /// Collective: every rank's `count` ints, rank after rank.
  std::vector<int> allGather(const int* values, int count);
  /// The lock every MPI call of an encode takes.
  std::mutex& Lock()
  {
    return this->Mutex;
  }

private:
  vtkMultiProcessController* Controller;
  std::mutex Mutex;
};

#endif
