// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkAFAMVolumeMapper
 * @brief   Renders Adaptive-FAM micro-models out of core through Core's ray caster.
 *
 * The mapper opens the .afam file itself (FileName, or the file named in the field data of its
 * input multiblock as produced by vtkAFAMReader / vtkAFAMEncoder), so only the index is held in
 * memory and payloads are read by Core's cache on demand. Per frame it converts the active
 * camera to the volume's normalised frame, the volume property's colour and scalar-opacity
 * transfer functions, shading and sample distance to Core's types, asks Core for an RGBA image of
 * the viewport size and blends it (premultiplied alpha) over what the render window holds.
 *
 * Depth of opaque geometry is not yet passed to Core: the volume is blended over the scene.
 */
#ifndef vtkAFAMVolumeMapper_h
#define vtkAFAMVolumeMapper_h

#include "vtkAFAMModule.h" // for export macro
#include "vtkVolumeMapper.h"

#include <memory> // for std::unique_ptr

class vtkAFAMCoreRenderer;

class VTKAFAM_EXPORT vtkAFAMVolumeMapper : public vtkVolumeMapper
{
public:
  static vtkAFAMVolumeMapper* New();
  vtkTypeMacro(vtkAFAMVolumeMapper, vtkVolumeMapper);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /// The .afam file to render. Default: none, then the file named by the input's field data.
  vtkSetFilePathMacro(FileName);
  vtkGetFilePathMacro(FileName);
  ///@}

  ///@{
  /// LOD policy: 0 = the paper's distance bands (default), 1 = screen-space error.
  vtkSetClampMacro(LodPolicy, int, 0, 1);
  vtkGetMacro(LodPolicy, int);
  ///@}

  ///@{
  /// RAM cache budget for micro-models in MB. Default 512, range [16, 1e6].
  vtkSetClampMacro(CacheBudgetMB, double, 16.0, 1e6);
  vtkGetMacro(CacheBudgetMB, double);
  ///@}

  ///@{
  /// Prefetcher: 0 none (default), 1 linear extrapolation of the camera path.
  vtkSetClampMacro(Prefetcher, int, 0, 1);
  vtkGetMacro(Prefetcher, int);
  ///@}

  ///@{
  /// Use the CUDA kernel when a usable GPU exists (default on); the CPU ray caster otherwise.
  vtkSetMacro(UseGpu, bool);
  vtkGetMacro(UseGpu, bool);
  vtkBooleanMacro(UseGpu, bool);
  ///@}

  ///@{
  /// Sample distance along rays in world units; <= 0 (default) uses the volume property's
  /// scalar opacity unit distance / 2.
  vtkSetMacro(SampleDistance, double);
  vtkGetMacro(SampleDistance, double);
  ///@}

  ///@{
  /// CPU threads for the CPU ray caster, 0 = all cores (default).
  vtkSetClampMacro(NumberOfThreads, int, 0, 1024);
  vtkGetMacro(NumberOfThreads, int);
  ///@}

  ///@{
  /// Statistics of the last frame (read only).
  vtkGetMacro(LastCachingTime, double);
  vtkGetMacro(LastRenderTime, double);
  vtkGetMacro(LastTotalTime, double);
  vtkGetMacro(LastCacheHits, vtkTypeInt64);
  vtkGetMacro(LastCacheMisses, vtkTypeInt64);
  vtkGetMacro(LastCulledBlocks, vtkTypeInt64);
  vtkGetMacro(LastVisibleBlocks, vtkTypeInt64);
  vtkGetMacro(LastBytesRead, vtkTypeInt64);
  vtkGetMacro(LastUsedGpu, bool);
  vtkGetMacro(NumberOfFrames, vtkTypeInt64);
  ///@}

  void Render(vtkRenderer* ren, vtkVolume* vol) override;
  double* GetBounds() override;
  using vtkVolumeMapper::GetBounds;
  void ReleaseGraphicsResources(vtkWindow*) override {}

protected:
  vtkAFAMVolumeMapper();
  ~vtkAFAMVolumeMapper() override;
  int FillInputPortInformation(int port, vtkInformation* info) override;

  /// The file to use now: FileName, else the input's field data. Empty when none.
  std::string ResolveFileName();
  /// Opens the file in Core when it changed; false (and an error) when it cannot.
  bool EnsureOpen();

  char* FileName = nullptr;
  int LodPolicy = 0;
  double CacheBudgetMB = 512;
  int Prefetcher = 0;
  bool UseGpu = true;
  double SampleDistance = 0;
  int NumberOfThreads = 0;

  double LastCachingTime = 0, LastRenderTime = 0, LastTotalTime = 0;
  vtkTypeInt64 LastCacheHits = 0, LastCacheMisses = 0, LastCulledBlocks = 0;
  vtkTypeInt64 LastVisibleBlocks = 0, LastBytesRead = 0, NumberOfFrames = 0;
  bool LastUsedGpu = false;

  std::unique_ptr<vtkAFAMCoreRenderer> Core;

private:
  vtkAFAMVolumeMapper(const vtkAFAMVolumeMapper&) = delete;
  void operator=(const vtkAFAMVolumeMapper&) = delete;
};

#endif
