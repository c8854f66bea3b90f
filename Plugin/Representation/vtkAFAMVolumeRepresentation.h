// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkAFAMVolumeRepresentation
 * @brief   ParaView representation "Adaptive-FAM Volume": renders .afam micro-models with
 *          vtkAFAMVolumeMapper.
 *
 * Its input is the metadata multiblock of vtkAFAMReader or vtkAFAMEncoder. Only the outline is
 * delivered through ParaView's data-delivery path; the mapper opens the .afam file named in the
 * input's field data itself and streams payloads through Core's cache (out of core). Colour and
 * opacity transfer functions, shading and the opacity unit distance arrive through the properties
 * inherited from vtkVolumeRepresentation, exactly as for ParaView's own "Volume".
 *
 * Under MPI (pvbatch, pvserver) every rank renders its share: the mapper draws one box of finest
 * blocks per rank (afam::rankBox, the same split on every rank from the file alone), with its own
 * file handle, cache, loads and GPU, and the representation declares each rank's box to
 * ParaView's ordered compositing, so that IceT blends the ranks' images in visibility order into
 * the image of one rank. Connected to pvserver, the view
 * always renders on the server (the representation requires distributed rendering), whatever
 * the remote-render threshold, since only the server can read the file.
 */
#ifndef vtkAFAMVolumeRepresentation_h
#define vtkAFAMVolumeRepresentation_h

#include "vtkAFAMParaViewModule.h" // for export macro
#include "vtkImageData.h"          // for vtkNew<vtkImageData>
#include "vtkNew.h"                // for vtkNew
#include "vtkVolumeRepresentation.h"

#include <string> // for std::string

class vtkAFAMVolumeMapper;
class vtkImageData;
class vtkPolyDataMapper;

class VTKAFAMPARAVIEW_EXPORT vtkAFAMVolumeRepresentation : public vtkVolumeRepresentation
{
public:
  static vtkAFAMVolumeRepresentation* New();
  vtkTypeMacro(vtkAFAMVolumeRepresentation, vtkVolumeRepresentation);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  int ProcessViewRequest(vtkInformationRequestKey* request_type,
    vtkInformation* inInfo,
    vtkInformation* outInfo) override;

  /// Shows or hides the volume.
  void SetVisibility(bool visible) override;

  ///@{
  /// Forwarded to vtkVolumeProperty.
  void SetShade(bool);
  void SetAmbient(double);
  void SetDiffuse(double);
  void SetSpecular(double);
  void SetSpecularPower(double);
  ///@}

  ///@{
  /// Forwarded to vtkAFAMVolumeMapper (see there for defaults and ranges).
  void SetLodPolicy(int);
  void SetLodPixelBudget(double);
  void SetDrawMissingValues(bool);
  void SetCacheBudgetMB(double);
  void SetPrefetcher(int);
  void SetRenderDevice(int);
  void SetDepthCompositing(bool);
  void SetSampleDistance(double);
  void SetNumberOfThreads(int);
  void SetAutoAdjustImageScale(bool);
  void SetMinimumImageScale(double);
  void SetInteractiveMissBudget(double);
  void SetBlendMode(int);
  ///@}

  ///@{
  /// Statistics of the last frame rendered by this process (read from the mapper).
  double GetLastCachingTime();
  double GetLastRenderTime();
  double GetLastTotalTime();
  vtkTypeInt64 GetLastCacheHits();
  vtkTypeInt64 GetLastCacheMisses();
  vtkTypeInt64 GetLastBytesRead();
  vtkTypeInt64 GetLastCacheBytes();
  vtkTypeInt64 GetLastCulledBlocks();
  vtkTypeInt64 GetLastVisibleBlocks();
  vtkTypeInt64 GetNumberOfFrames();
  int GetLastUsedGpu();
  /// 1 when the last frame's image went from the GPU to the window without the host (CUDA-OpenGL
  /// interop), 0 otherwise; GetLastInteropProblem says why not where OpenGL cannot share buffers.
  int GetLastImageOnDevice();
  const char* GetLastInteropProblem();
  vtkTypeInt64 GetLastDepthLimitedPixels();
  double GetLastImageScale();
  const char* GetLastDeviceMessage();
  vtkTypeInt64 GetLastGpuModelsUploaded();
  vtkTypeInt64 GetNumberOfRendererBuilds();
  const char* GetLastSettingWarning();
  /// What the last frame left behind under its miss budget (vtkAFAMVolumeMapper): blocks drawn
  /// from a coarser resident level, blocks not drawn at their own level, and their bytes.
  vtkTypeInt64 GetLastStandInBlocks();
  vtkTypeInt64 GetLastBlocksBehind();
  vtkTypeInt64 GetLastBytesBehind();
  ///@}

  vtkAFAMVolumeMapper* GetVolumeMapper()
  {
    return this->Mapper;
  }

protected:
  vtkAFAMVolumeRepresentation();
  ~vtkAFAMVolumeRepresentation() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  bool AddToView(vtkView* view) override;
  bool RemoveFromView(vtkView* view) override;

  vtkNew<vtkAFAMVolumeMapper> Mapper;
  vtkNew<vtkPolyDataMapper> OutlineMapper;
  vtkNew<vtkImageData> StandIn;
  std::string FileName;
  bool RendersHere = false;
  /// Under MPI: checks that every rank opened one file (afam::ranksFileDisagreement); when not,
  /// hides the volume on every rank with one error each. Collective: REQUEST_UPDATE calls it.
  void AgreeOnFile();
  std::string RanksProblem; // the last disagreement reported (each is reported once)
  // This rank's box in world coordinates (what it draws and declares for ordered compositing).
  double RankBounds[6] = { 0, -1, 0, -1, 0, -1 };

private:
  vtkAFAMVolumeRepresentation(const vtkAFAMVolumeRepresentation&) = delete;
  void operator=(const vtkAFAMVolumeRepresentation&) = delete;
};

#endif
