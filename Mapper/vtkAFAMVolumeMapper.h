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
 * Resources apart from settings: the RAM cache, the prefetch thread and the GPU model pool live
 * as long as the file, CacheBudgetMB, Prefetcher, RenderDevice and NumberOfThreads stay the same
 * (NumberOfRendererBuilds counts them). Transfer functions, shading, blend mode, sample distance
 * and LOD policy go with each frame: editing them reads and uploads only the models that become
 * visible. Unusable settings (a transfer function without points or with NaN, a
 * ScalarOpacityUnitDistance or sample distance that is not > 0) give one warning naming the
 * setting and its value, and the last usable value is drawn (GetLastSettingWarning).
 *
 * Placement: the camera (perspective or parallel projection) is mapped from the world through
 * the inverse of the vtkVolume's matrix (position, orientation, scale, origin, user matrix) into
 * the data, then each axis of the data box onto [-1, 1] (the paper's normalised frame). Every
 * pixel's ray lands on the world ray it stands for, also for non-cubic volumes and non-uniform
 * scales; steps are SampleDistance long in the world in every direction, and opacity follows
 * the property's ScalarOpacityUnitDistance in world units.
 *
 * Depth compositing: before casting, the mapper reads the viewport's z-buffer (the opaque geometry
 * VTK has drawn), converts every pixel's window depth back to the distance along that pixel's ray
 * (inverse of the camera's composite projection: perspective depth linearised) and hands Core a
 * per-pixel ray length limit, so no sample behind an opaque surface is composited.
 *
 * Blend modes: composite, maximum, minimum and average intensity projection (vtkVolumeMapper's
 * SetBlendMode); the others are drawn composite with one warning.
 *
 * Render device: with RenderDevice Auto or GPU the frame is cast by the CUDA renderer when the
 * build has it (afam_cuda) and a usable GPU is present, else by the CPU ray caster; GPU explicitly
 * asked for but unusable gives one vtkWarning saying why (Auto says it once through vtkLog).
 */
#ifndef vtkAFAMVolumeMapper_h
#define vtkAFAMVolumeMapper_h

#include "vtkAFAMModule.h" // for export macro
#include "vtkVolumeMapper.h"

#include <array>    // for std::array
#include <cstdint>  // for uint8_t
#include <memory>   // for std::unique_ptr
#include <optional> // for std::optional
#include <string>   // for std::string
#include <vector>   // for std::vector

class vtkAFAMCoreRenderer;
class vtkAFAMCudaGLBuffer;
class vtkAFAMImageDraw;
class vtkOpenGLRenderWindow;
class vtkVolumeProperty;
struct vtkAFAMFrameStats;
namespace afam
{
struct ImageRGBA;
}

class VTKAFAM_EXPORT vtkAFAMVolumeMapper : public vtkVolumeMapper
{
public:
  static vtkAFAMVolumeMapper* New();
  vtkTypeMacro(vtkAFAMVolumeMapper, vtkVolumeMapper);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /// The .afam file to render. Default: none, then the file named by the input's field data.
  /// FileName alone is enough: no input connection is needed.
  vtkSetFilePathMacro(FileName);
  vtkGetFilePathMacro(FileName);
  /// The time step of a run of steps (format version 3) drawn when FileName is set (default 0;
  /// with an input connection, the step the input's time chose). Another step opens anew.
  vtkSetClampMacro(TimeStep, vtkTypeInt64, 0, VTK_TYPE_INT64_MAX);
  vtkGetMacro(TimeStep, vtkTypeInt64);
  ///@}

  enum LodPolicies
  {
    LOD_DISTANCE_BANDS = 0, ///< the paper's bands of distance from the eye
    LOD_SCREEN_SPACE = 1    ///< the coarsest level whose samples project to at most a pixel
  };

  ///@{
  /// LOD policy: LOD_SCREEN_SPACE (default: a still frame as sharp as VTK's own volume mappers
  /// draw the samples) or LOD_DISTANCE_BANDS (the paper's benchmarks).
  vtkSetClampMacro(LodPolicy, int, LOD_DISTANCE_BANDS, LOD_SCREEN_SPACE);
  vtkGetMacro(LodPolicy, int);
  void SetLodPolicyToDistanceBands()
  {
    this->SetLodPolicy(LOD_DISTANCE_BANDS);
  }
  void SetLodPolicyToScreenSpace()
  {
    this->SetLodPolicy(LOD_SCREEN_SPACE);
  }
  ///@}

  ///@{
  /// Screen-space LOD: a region is refined while its sample spacing projects to more than this
  /// many pixels. Default 1 (every sample the screen can show), range [0.25, 64].
  vtkSetClampMacro(LodPixelBudget, double, 0.25, 64.0);
  vtkGetMacro(LodPixelBudget, double);
  ///@}

  ///@{
  /// Missing samples (NaN, the file's fill value): with DrawMissingValues on they are drawn with
  /// the colour transfer function's NanColor and NanOpacity (ParaView's "NaN Color" and "NaN
  /// Opacity"; the opacity per ScalarOpacityUnitDistance, like the scalar opacity); off (default)
  /// they are empty space. Off by default because VTK's NanOpacity defaults to 1, which would
  /// fill every hole of a volume opaque.
  vtkSetMacro(DrawMissingValues, bool);
  vtkGetMacro(DrawMissingValues, bool);
  vtkBooleanMacro(DrawMissingValues, bool);
  ///@}

  ///@{
  /// RAM cache budget for micro-models in MB. Default 512, range [16, 1e6]. A change starts a new
  /// cache (and GPU pool); transfer functions, shading and sample distance do not.
  vtkSetClampMacro(CacheBudgetMB, double, 16.0, 1e6);
  vtkGetMacro(CacheBudgetMB, double);
  ///@}

  enum Prefetchers
  {
    PREFETCH_NONE = 0,  ///< no prefetching
    PREFETCH_LINEAR = 1 ///< linear extrapolation of the camera path
  };

  ///@{
  /// Prefetcher: PREFETCH_NONE (default) or PREFETCH_LINEAR.
  vtkSetClampMacro(Prefetcher, int, PREFETCH_NONE, PREFETCH_LINEAR);
  vtkGetMacro(Prefetcher, int);
  void SetPrefetcherToNone()
  {
    this->SetPrefetcher(PREFETCH_NONE);
  }
  void SetPrefetcherToLinear()
  {
    this->SetPrefetcher(PREFETCH_LINEAR);
  }
  ///@}

  enum RenderDevices
  {
    DEVICE_AUTO = 0, ///< the CUDA renderer when built and a GPU is usable, else the CPU
    DEVICE_CPU = 1,  ///< always the CPU ray caster
    DEVICE_GPU = 2   ///< the CUDA renderer; the CPU with one warning when it is unusable
  };

  ///@{
  /// Ray caster: DEVICE_AUTO (default), DEVICE_CPU or DEVICE_GPU (see above).
  void SetRenderDevice(int device);
  vtkGetMacro(RenderDevice, int);
  void SetRenderDeviceToAuto()
  {
    this->SetRenderDevice(DEVICE_AUTO);
  }
  void SetRenderDeviceToCPU()
  {
    this->SetRenderDevice(DEVICE_CPU);
  }
  void SetRenderDeviceToGPU()
  {
    this->SetRenderDevice(DEVICE_GPU);
  }
  /// The device that cast the last frame: DEVICE_CPU or DEVICE_GPU.
  int GetLastUsedRenderDevice()
  {
    return this->LastUsedGpu ? DEVICE_GPU : DEVICE_CPU;
  }
  ///@}

  /// The blend mode the last frame was drawn with (composite for modes this mapper lacks).
  vtkGetMacro(LastUsedBlendMode, int);

  /// True when this build contains the CUDA renderer (whether or not a GPU is present).
  static bool HasCudaRenderer();

  ///@{
  /// Stop rays at opaque geometry already in the z-buffer (default on). Off: the volume is
  /// blended over the scene regardless of depth.
  vtkSetMacro(DepthCompositing, bool);
  vtkGetMacro(DepthCompositing, bool);
  vtkBooleanMacro(DepthCompositing, bool);
  ///@}

  ///@{
  /// Sample distance along rays in world units; <= 0 (default): the sample spacing of the
  /// file's finest level (its smallest axis), so that the default image is close to a finely
  /// sampled one; opacities are corrected for the step either way.
  vtkSetMacro(SampleDistance, double);
  vtkGetMacro(SampleDistance, double);
  ///@}

  ///@{
  /// Shift each pixel's samples along its ray by a fraction of a step that depends on the pixel
  /// only (stable between frames), as VTK's UseJittering does: the banding a regular lattice
  /// draws through a volume becomes fine noise. Default on.
  vtkSetMacro(UseJittering, bool);
  vtkGetMacro(UseJittering, bool);
  vtkBooleanMacro(UseJittering, bool);
  ///@}

  ///@{
  /// Interactive frames (the render window's DesiredUpdateRate above 1, as while the mouse
  /// drags) are cast at a reduced image size so that they fit the time VTK allots the volume,
  /// estimated from the previous frames' time per pixel, and drawn scaled up; still frames are
  /// always full size. Default on. The scale (of width and height) never goes below
  /// MinimumImageScale (default 0.25, range [0.05, 1]).
  vtkSetMacro(AutoAdjustImageScale, bool);
  vtkGetMacro(AutoAdjustImageScale, bool);
  vtkBooleanMacro(AutoAdjustImageScale, bool);
  vtkSetClampMacro(MinimumImageScale, double, 0.05, 1.0);
  vtkGetMacro(MinimumImageScale, double);
  ///@}

  ///@{
  /// Milliseconds an interactive frame waits for the micro-models it misses (read and decoded by
  /// every core at once); a block still loading then is drawn from its nearest resident coarser
  /// level and refined in the next frames. Still frames always wait for every block, so the image
  /// after interaction is exact. Default 20; below 0: interactive frames wait for every block too.
  vtkSetMacro(InteractiveMissBudget, double);
  vtkGetMacro(InteractiveMissBudget, double);
  ///@}

  ///@{
  /**
   * Sort-last rendering over MPI ranks (pvbatch, pvserver): this mapper draws only rank `rank`'s
   * share of `ranks`, one box of finest blocks from a k-d split by work that every rank computes
   * alike from the file (afam::rankBox), its rays clipped to the box on the one global lattice of
   * samples, so that the ranks' images blended in visibility order (ordered compositing, with the
   * boxes GetRankBounds gives) are the image of one mapper. Its cache, loads and prefetch hold
   * only the blocks that meet its box. Composite blending only: the maximum, minimum and average
   * of several images are not their "over" blend, so in those modes rank 0 draws the whole volume
   * and the other ranks nothing. Default 0 of 1: the whole volume. A rank outside 0 .. ranks-1
   * is an error the frame reports.
   */
  void SetRank(int rank, int ranks);
  vtkGetMacro(Rank, int);
  vtkGetMacro(NumberOfRanks, int);
  /// World bounds of this rank's box in the mapper's file; false, bounds untouched, when there
  /// is no readable file or the box is empty (more ranks than finest blocks: it draws nothing).
  bool GetRankBounds(double bounds[6]);
  /// A fingerprint of the file this mapper draws (afam::contentFingerprint), 0 when it cannot
  /// open it: ranks compare theirs to know that they draw one file.
  vtkTypeUInt64 GetFileFingerprint();
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
  /// The last frame's host round trips through OpenGL, in seconds: reading the depth buffer for
  /// depth compositing (0 when off, or when the renderer holds nothing visible but volumes, so
  /// that no opaque geometry can have written depth), and drawing the cast image into the viewport
  /// (its copy into a texture, from the host or from the GPU's buffer, and a quad).
  /// LastTotalTime holds them, LastRenderTime and LastCachingTime do not.
  vtkGetMacro(LastDepthReadTime, double);
  vtkGetMacro(LastDrawTime, double);
  ///@{
  /// Frames cast on the GPU reach the window through CUDA-OpenGL interop where the OpenGL allows
  /// it (default on); off: they come back to the host and are uploaded (the fallback path, kept
  /// for comparison and for drivers that misbehave).
  vtkSetMacro(GpuImageInterop, bool);
  vtkGetMacro(GpuImageInterop, bool);
  vtkBooleanMacro(GpuImageInterop, bool);
  ///@}
  /// True when the last frame's image went from the GPU to the window without the host: CUDA
  /// cast it into an OpenGL pixel buffer (CUDA-OpenGL interop), drawn from there (no download, no
  /// upload; LastGpuDownloadTime 0). False for CPU frames, and where OpenGL cannot share buffers
  /// with CUDA (e.g. Mesa): GetLastInteropProblem says why, found once, not tried again until the
  /// window's graphics resources are released.
  vtkGetMacro(LastImageOnDevice, bool);
  const char* GetLastInteropProblem()
  {
    return this->LastInteropProblem.c_str();
  }
  /// The GPU's own times for the last frame (CUDA events), in seconds: uploading the models not
  /// yet resident, ray casting, and copying the image back to the host (part of LastRenderTime);
  /// -1 when the frame was cast on the CPU.
  vtkGetMacro(LastGpuUploadTime, double);
  vtkGetMacro(LastGpuKernelTime, double);
  vtkGetMacro(LastGpuDownloadTime, double);
  vtkGetMacro(LastCacheHits, vtkTypeInt64);
  vtkGetMacro(LastCacheMisses, vtkTypeInt64);
  vtkGetMacro(LastCulledBlocks, vtkTypeInt64);
  vtkGetMacro(LastVisibleBlocks, vtkTypeInt64);
  vtkGetMacro(LastBytesRead, vtkTypeInt64);
  /// Bytes of decoded models in the RAM cache after the last frame (what CacheBudgetMB bounds).
  vtkGetMacro(LastCacheBytes, vtkTypeInt64);
  vtkGetMacro(LastUsedGpu, bool);
  /// Models the last frame copied into the GPU's model pool (0: all were resident); -1 when the
  /// frame was cast on the CPU.
  vtkGetMacro(LastGpuModelsUploaded, vtkTypeInt64);
  /// Times the mapper built its renderer (RAM cache, prefetch thread, GPU pool): the first frame,
  /// a new file, and changes of CacheBudgetMB, Prefetcher, RenderDevice or NumberOfThreads.
  /// Editing the transfer functions, shading, blend mode, sample distance or LOD policy does not.
  vtkGetMacro(NumberOfRendererBuilds, vtkTypeInt64);
  /// What was wrong with the last frame's settings and what was kept instead (empty: nothing).
  const char* GetLastSettingWarning()
  {
    return this->LastSettingWarning.c_str();
  }
  /// Damaged micro-models (checksum mismatch) in the last frame's selection, drawn from the nearest
  /// intact level instead; and all the blocks of the file found damaged so far. Each is reported
  /// once with a vtkWarning naming the file, level and block, and never read again.
  vtkGetMacro(LastDamagedBlocks, vtkTypeInt64);
  vtkGetMacro(KnownDamagedBlocks, vtkTypeInt64);
  /// Blocks of the last frame drawn from a coarser level because they were still loading when
  /// its miss budget ran out (InteractiveMissBudget); 0: the frame is exact.
  vtkGetMacro(LastStandInBlocks, vtkTypeInt64);
  /// Blocks of the last frame not drawn at their own level because its miss budget ran out (the
  /// stand-ins, and blocks with no resident coarser level), and their models' decoded bytes; they
  /// load for the next frames. 0: the frame is exact.
  vtkGetMacro(LastBlocksBehind, vtkTypeInt64);
  vtkGetMacro(LastBytesBehind, vtkTypeInt64);
  /// Pixels of the last frame whose rays were cut short by opaque geometry.
  vtkGetMacro(LastDepthLimitedPixels, vtkTypeInt64);
  /// Image scale of the last frame (1 = full size; below 1 for interactive frames).
  vtkGetMacro(LastImageScale, double);
  vtkGetMacro(NumberOfFrames, vtkTypeInt64);
  /// Why the GPU was not used (empty when it was, or when the CPU was asked for).
  const char* GetLastDeviceMessage()
  {
    return this->LastDeviceMessage.c_str();
  }
  ///@}

  void Render(vtkRenderer* ren, vtkVolume* vol) override;
  double* GetBounds() override;
  using vtkVolumeMapper::GetBounds;
  void ReleaseGraphicsResources(vtkWindow* window) override;

protected:
  vtkAFAMVolumeMapper();
  ~vtkAFAMVolumeMapper() override;
  int FillInputPortInformation(int port, vtkInformation* info) override;

  /// The file to use now: FileName, else the input's field data. Empty when none.
  std::string ResolveFileName(); // also sets ResolvedStep (the input tree's time step)
  long long ResolvedStep = 0;
  /// Opens the file in Core when it changed; false (and an error, once per distinct error) when
  /// it cannot.
  bool EnsureOpen();
  /// "rank R of N: " when drawn by several ranks, else empty: what begins this rank's errors.
  std::string RankPrefix() const;
  /// Core's frame; a file changed on disk is opened again and drawn anew in the same frame. False
  /// (and an error) when nothing can be drawn.
  struct Frame;
  bool RenderCore(Frame& frame, afam::ImageRGBA& image, vtkAFAMFrameStats& stats);
  /// The steps of Render, in order. Each false means nothing is drawn (and an error was given).
  bool PlanImage(vtkRenderer* ren, vtkVolume* vol, Frame& frame);
  bool MapCamera(vtkRenderer* ren, vtkVolume* vol, Frame& frame);
  void ReadFrameSettings(vtkVolumeProperty* property, Frame& frame);
  /// The sample distance SampleDistance <= 0 stands for: the finest level's smallest
  /// sample spacing (`spacing`, the file's), in world units.
  static double DefaultSampleDistance(const double spacing[3]);
  /// Per-pixel ray length limits from the viewport's z-buffer (the opaque geometry drawn so far);
  /// false when it was not read (depth compositing off, or nothing but volumes to draw depth).
  bool ReadDepthLimits(vtkRenderer* ren, Frame& frame);
  /// The GPU's way (CUDA-OpenGL interop, frames whose image goes to CUDA's buffer): the z-buffer
  /// copied on the GPU into a buffer CUDA reads, limits computed there. False: not possible here
  /// (the host path follows).
  bool ReadDepthOnGpu(vtkRenderer* ren,
    int x0,
    int y0,
    int w,
    int h,
    const std::array<double, 16>& ndcToWorld,
    Frame& frame);
  void RecordStatistics(const Frame& frame, const vtkAFAMFrameStats& stats);

  char* FileName = nullptr;
  vtkTypeInt64 TimeStep = 0;
  int LodPolicy = LOD_SCREEN_SPACE;
  double LodPixelBudget = 1.0;
  bool DrawMissingValues = false;
  double CacheBudgetMB = 512;
  int Prefetcher = PREFETCH_NONE;
  int RenderDevice = DEVICE_AUTO;
  bool DepthCompositing = true;
  bool WarnedDevice = false;
  std::string ReportedInteropProblem; // the interop problem last said (once per problem)
  // The GPU of the window's OpenGL context (vtkAFAMCudaGLBuffer::ContextDeviceUuid), asked once a
  // window: the GPU renderer is built on that CUDA device where it can be (interop).
  const void* UuidWindow = nullptr;
  std::optional<std::array<uint8_t, 16>> OpenGLDevice;
  bool WarnedBlendMode = false;
  double SampleDistance = 0;
  bool UseJittering = true;
  int NumberOfThreads = 0;
  int Rank = 0, NumberOfRanks = 1;
  bool AutoAdjustImageScale = true;
  double MinimumImageScale = 0.25;
  double InteractiveMissBudget = 20;
  double LastImageScale = 1;
  double SecondsPerPixel = 0; ///< running estimate of a frame's time per cast pixel

  double LastCachingTime = 0, LastRenderTime = 0, LastTotalTime = 0;
  double LastDepthReadTime = 0, LastDrawTime = 0;
  double LastGpuUploadTime = -1, LastGpuKernelTime = -1, LastGpuDownloadTime = -1;
  vtkTypeInt64 LastCacheHits = 0, LastCacheMisses = 0, LastCulledBlocks = 0;
  vtkTypeInt64 LastVisibleBlocks = 0, LastBytesRead = 0, NumberOfFrames = 0, LastCacheBytes = 0;
  vtkTypeInt64 LastDamagedBlocks = 0, KnownDamagedBlocks = 0, LastStandInBlocks = 0;
  vtkTypeInt64 LastBlocksBehind = 0, LastBytesBehind = 0;
  bool LastUsedGpu = false;
  int LastUsedBlendMode = COMPOSITE_BLEND;
  vtkTypeInt64 LastGpuModelsUploaded = -1, NumberOfRendererBuilds = 0;
  vtkTypeInt64 LastDepthLimitedPixels = 0;
  std::string LastDeviceMessage;
  std::string LastSettingWarning;
  std::string LastOpenError; ///< reported once, until the error changes or the file opens

  std::unique_ptr<vtkAFAMCoreRenderer> Core;
  std::unique_ptr<vtkAFAMImageDraw> Draw;
  std::unique_ptr<vtkAFAMCudaGLBuffer> DepthBuffer; // the z-buffer on its way to CUDA
  bool GpuImageInterop = true;
  bool LastImageOnDevice = false;
  std::string LastInteropProblem;

private:
  vtkAFAMVolumeMapper(const vtkAFAMVolumeMapper&) = delete;
  void operator=(const vtkAFAMVolumeMapper&) = delete;
};

#endif
