// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMControllerTeam.h"

#include "vtkCommunicator.h"
#include "vtkMultiProcessController.h"

vtkAFAMControllerTeam::vtkAFAMControllerTeam(vtkMultiProcessController* controller)
  : Controller(controller)
{
}

int vtkAFAMControllerTeam::rank() const
{
  return this->Controller->GetLocalProcessId();
}

int vtkAFAMControllerTeam::size() const
{
  return this->Controller->GetNumberOfProcesses();
}

void vtkAFAMControllerTeam::reduceRange(double& lo, double& hi)
{
  std::lock_guard<std::mutex> lock(this->Mutex);
  double in[2] = { lo, -hi }, out[2] = { 0, 0 };
  this->Controller->AllReduce(in, out, 2, vtkCommunicator::MIN_OP);
  lo = out[0];
  hi = -out[1];
}

void vtkAFAMControllerTeam::mergeFlags(std::vector<uint8_t>& flags)
{
  std::lock_guard<std::mutex> lock(this->Mutex);
  std::vector<uint8_t> merged(flags.size());
  this->Controller->AllReduce(
    flags.data(), merged.data(), static_cast<vtkIdType>(flags.size()), vtkCommunicator::MAX_OP);
  flags.swap(merged);
}

std::vector<std::vector<uint8_t>> vtkAFAMControllerTeam::gatherToFirst(
  const std::vector<uint8_t>& bytes)
{
  std::lock_guard<std::mutex> lock(this->Mutex);
  const int ranks = this->size();
  const vtkIdType mine = static_cast<vtkIdType>(bytes.size());
  std::vector<vtkIdType> lengths(static_cast<size_t>(ranks), 0), offsets(lengths.size() + 1, 0);
  this->Controller->Gather(&mine, lengths.data(), 1, 0);
  for (size_t r = 0; r < lengths.size(); ++r)
  {
    offsets[r + 1] = offsets[r] + lengths[r];
  }
  std::vector<uint8_t> all(this->rank() == 0 ? static_cast<size_t>(offsets.back()) : 0);
  uint8_t dummy = 0;
  this->Controller->GatherV(bytes.empty() ? &dummy : bytes.data(),
    all.empty() ? &dummy : all.data(),
    mine,
    lengths.data(),
    offsets.data(),
    0);
  std::vector<std::vector<uint8_t>> parts;
  if (this->rank() == 0)
  {
    for (size_t r = 0; r < lengths.size(); ++r)
    {
      parts.emplace_back(all.begin() + offsets[r], all.begin() + offsets[r + 1]);
    }
  }
  return parts;
}

int vtkAFAMControllerTeam::reduceMin(int value)
{
  std::lock_guard<std::mutex> lock(this->Mutex);
  int result = value;
  this->Controller->AllReduce(&value, &result, 1, vtkCommunicator::MIN_OP);
  return result;
}

std::string vtkAFAMControllerTeam::broadcast(const std::string& text, int root)
{
  std::lock_guard<std::mutex> lock(this->Mutex);
  vtkIdType length = static_cast<vtkIdType>(text.size());
  this->Controller->Broadcast(&length, 1, root);
  std::string result = this->rank() == root ? text : std::string(static_cast<size_t>(length), '\0');
  if (length > 0)
  {
    this->Controller->Broadcast(&result[0], length, root);
  }
  return result;
}

void vtkAFAMControllerTeam::broadcastFromFirst(std::vector<uint8_t>& bytes)
{
  std::lock_guard<std::mutex> lock(this->Mutex);
  vtkIdType length = static_cast<vtkIdType>(bytes.size());
  this->Controller->Broadcast(&length, 1, 0);
  bytes.resize(static_cast<size_t>(length));
  if (length > 0)
  {
    this->Controller->Broadcast(reinterpret_cast<char*>(bytes.data()), length, 0);
  }
}

std::vector<int> vtkAFAMControllerTeam::allGather(const int* values, int count)
{
  std::lock_guard<std::mutex> lock(this->Mutex);
  std::vector<int> all(static_cast<size_t>(count) * static_cast<size_t>(this->size()));
  this->Controller->AllGather(values, all.data(), count);
  return all;
}

std::string vtkAFAMControllerTeam::agreeOnError(const std::string& localError)
{
  const int failed = this->reduceMin(localError.empty() ? this->size() : this->rank());
  if (failed == this->size())
  {
    return std::string();
  }
  return "rank " + std::to_string(failed) + ": " + this->broadcast(localError, failed);
}
