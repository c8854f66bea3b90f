// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMFrameStatistics.h"

#include "vtkAFAMVolumeRepresentation.h"

#include "vtkCommunicator.h"
#include "vtkCompositeRepresentation.h"
#include "vtkMultiProcessController.h"
#include "vtkObjectFactory.h"

vtkStandardNewMacro(vtkAFAMFrameStatistics);

vtkAFAMFrameStatistics::vtkAFAMFrameStatistics() = default;
vtkAFAMFrameStatistics::~vtkAFAMFrameStatistics() = default;

void vtkAFAMFrameStatistics::SetRepresentation(vtkPVDataRepresentation* representation)
{
  this->Representation = representation;
  this->Modified();
}

namespace
{
vtkAFAMVolumeRepresentation* findVolumeRepresentation(vtkPVDataRepresentation* representation)
{
  if (auto* composite = vtkCompositeRepresentation::SafeDownCast(representation))
  {
    representation = composite->GetActiveRepresentation();
  }
  return vtkAFAMVolumeRepresentation::SafeDownCast(representation);
}
}

void vtkAFAMFrameStatistics::Gather()
{
  vtkTypeInt64 sums[3] = { 0, 0, 1 }; // bytes read, visible blocks, ranks
  double maxima[2] = { 0, 0 };        // bytes read, mapper time
  double scale = 1;                   // image scale of the last frame where blocks were drawn
  if (auto* volume = findVolumeRepresentation(this->Representation))
  {
    sums[0] = volume->GetLastBytesRead();
    sums[1] = volume->GetLastVisibleBlocks();
    maxima[0] = static_cast<double>(sums[0]);
    maxima[1] = volume->GetLastTotalTime();
    scale = sums[1] > 0 ? volume->GetLastImageScale() : 1.0;
  }
  vtkTypeInt64 drawing = sums[1] > 0 ? 1 : 0;
  vtkTypeInt64 onGpu = 0, interop = 0;  // this rank's last frame: cast on the GPU, through interop
  vtkTypeInt64 behind[3] = { 0, 0, 0 }; // stand-ins, blocks behind, bytes behind
  if (auto* volume = findVolumeRepresentation(this->Representation))
  {
    onGpu = volume->GetLastUsedGpu() ? 1 : 0;
    interop = volume->GetLastImageOnDevice() ? 1 : 0;
    behind[0] = volume->GetLastStandInBlocks();
    behind[1] = volume->GetLastBlocksBehind();
    behind[2] = volume->GetLastBytesBehind();
  }
  auto* controller = vtkMultiProcessController::GetGlobalController();
  if (controller && controller->GetNumberOfProcesses() > 1)
  {
    const vtkTypeInt64 local[6] = { sums[0], sums[1], sums[2], drawing, onGpu, interop };
    vtkTypeInt64 total[6];
    controller->AllReduce(local, total, 6, vtkCommunicator::SUM_OP);
    const vtkTypeInt64 localBehind[3] = { behind[0], behind[1], behind[2] };
    controller->AllReduce(localBehind, behind, 3, vtkCommunicator::SUM_OP);
    const double localMax[2] = { maxima[0], maxima[1] };
    controller->AllReduce(localMax, maxima, 2, vtkCommunicator::MAX_OP);
    const double localScale = scale;
    controller->AllReduce(&localScale, &scale, 1, vtkCommunicator::MIN_OP);
    sums[0] = total[0];
    sums[1] = total[1];
    sums[2] = total[2];
    drawing = total[3];
    onGpu = total[4];
    interop = total[5];
  }
  this->TotalBytesRead = sums[0];
  this->TotalVisibleBlocks = sums[1];
  this->NumberOfRanks = static_cast<int>(sums[2]);
  this->RanksDrawingBlocks = static_cast<int>(drawing);
  this->MaxBytesRead = static_cast<vtkTypeInt64>(maxima[0]);
  this->MaxTotalTime = maxima[1];
  this->MinImageScale = scale;
  this->RanksOnGpu = static_cast<int>(onGpu);
  this->RanksThroughInterop = static_cast<int>(interop);
  this->TotalStandInBlocks = behind[0];
  this->TotalBlocksBehind = behind[1];
  this->TotalBytesBehind = behind[2];
}

void vtkAFAMFrameStatistics::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Representation: " << this->Representation.GetPointer() << "\n";
  os << indent << "NumberOfRanks: " << this->NumberOfRanks << "\n";
  os << indent << "RanksDrawingBlocks: " << this->RanksDrawingBlocks << "\n";
  os << indent << "TotalBytesRead: " << this->TotalBytesRead << "\n";
  os << indent << "MaxBytesRead: " << this->MaxBytesRead << "\n";
  os << indent << "TotalVisibleBlocks: " << this->TotalVisibleBlocks << "\n";
  os << indent << "MaxTotalTime: " << this->MaxTotalTime << "\n";
  os << indent << "MinImageScale: " << this->MinImageScale << "\n";
  os << indent << "RanksOnGpu: " << this->RanksOnGpu << "\n";
  os << indent << "RanksThroughInterop: " << this->RanksThroughInterop << "\n";
  os << indent << "TotalStandInBlocks: " << this->TotalStandInBlocks << "\n";
  os << indent << "TotalBlocksBehind: " << this->TotalBlocksBehind << "\n";
  os << indent << "TotalBytesBehind: " << this->TotalBytesBehind << "\n";
}
