// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkAFAMFrameStatistics
 * @brief   Last-frame figures of an "Adaptive-FAM Volume" display summed over the ranks that
 *          render it, readable from a client.
 *
 * A client's own copy of the representation never renders when the view renders on the server,
 * so the display's AFAMLast... properties read from a client are those of that idle copy. This
 * object lives on the server processes only (its proxy says so): Gather() is run by every rank,
 * combines their figures, and rank 0 answers the information properties. In builtin mode and
 * pvbatch it sees the one or several local ranks the same way.
 */
#ifndef vtkAFAMFrameStatistics_h
#define vtkAFAMFrameStatistics_h

#include "vtkAFAMParaViewModule.h" // for export macro
#include "vtkObject.h"
#include "vtkWeakPointer.h" // for vtkWeakPointer

class vtkPVDataRepresentation;

class VTKAFAMPARAVIEW_EXPORT vtkAFAMFrameStatistics : public vtkObject
{
public:
  static vtkAFAMFrameStatistics* New();
  vtkTypeMacro(vtkAFAMFrameStatistics, vtkObject);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// The display: a vtkAFAMVolumeRepresentation, or a composite representation (ParaView's
  /// display) whose active representation is one. Not reference counted.
  void SetRepresentation(vtkPVDataRepresentation* representation);

  /// Collective: every process holding the representation must call it (a proxy command does).
  void Gather();

  ///@{
  /// Results of the last Gather() (complete on rank 0).
  vtkGetMacro(NumberOfRanks, int);
  vtkGetMacro(RanksDrawingBlocks, int);
  vtkGetMacro(TotalBytesRead, vtkTypeInt64);
  vtkGetMacro(MaxBytesRead, vtkTypeInt64);
  vtkGetMacro(TotalVisibleBlocks, vtkTypeInt64);
  vtkGetMacro(MaxTotalTime, double);
  /// Smallest image scale among the ranks that drew blocks (below 1 in interactive frames that
  /// the mapper shrank to meet the frame budget).
  vtkGetMacro(MinImageScale, double);
  /// Ranks whose last frame was cast on the GPU, and those whose last frame's image went from the
  /// GPU to the window without the host (CUDA-OpenGL interop).
  vtkGetMacro(RanksOnGpu, int);
  vtkGetMacro(RanksThroughInterop, int);
  /// What the last frame left behind under its miss budget, summed over the ranks: blocks drawn
  /// from a coarser resident level, blocks not drawn at their own level, and their bytes.
  vtkGetMacro(TotalStandInBlocks, vtkTypeInt64);
  vtkGetMacro(TotalBlocksBehind, vtkTypeInt64);
  vtkGetMacro(TotalBytesBehind, vtkTypeInt64);
  ///@}

protected:
  vtkAFAMFrameStatistics();
  ~vtkAFAMFrameStatistics() override;

  vtkWeakPointer<vtkPVDataRepresentation> Representation;
  int NumberOfRanks = 0;
  int RanksDrawingBlocks = 0;
  vtkTypeInt64 TotalBytesRead = 0;
  vtkTypeInt64 MaxBytesRead = 0;
  vtkTypeInt64 TotalVisibleBlocks = 0;
  double MaxTotalTime = 0;
  double MinImageScale = 1;
  int RanksOnGpu = 0;
  int RanksThroughInterop = 0;
  vtkTypeInt64 TotalStandInBlocks = 0;
  vtkTypeInt64 TotalBlocksBehind = 0;
  vtkTypeInt64 TotalBytesBehind = 0;

private:
  vtkAFAMFrameStatistics(const vtkAFAMFrameStatistics&) = delete;
  void operator=(const vtkAFAMFrameStatistics&) = delete;
};

#endif
