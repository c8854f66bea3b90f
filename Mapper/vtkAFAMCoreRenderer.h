// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// Private helper of vtkAFAMVolumeMapper (not wrapped, not installed): the one place where the
// mapper calls Core's out-of-core renderer. It keeps one afam::Renderer (RAM cache, prefetch
// thread, and the GPU caster with its model pool, from afam::makeGpuCaster) for as long as the
// file and the resources stay the same, and hands each frame its own settings and targets.
// Everything VTK-specific (reading the camera, the transfer functions, compositing) stays in the
// mapper; everything numeric stays in Core. No CUDA here: the GPU sits behind afam::FrameCaster.
#ifndef vtkAFAMCoreRenderer_h
#define vtkAFAMCoreRenderer_h

#include "afam/ranks/device_selection.hpp"
#include "afam/scene/camera.hpp"
#include "afam/render/frame_caster.hpp"
#include "afam/render/frame_settings.hpp"
#include "afam/render/image.hpp"

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

struct vtkAFAMFrameRequest
{
  afam::Camera Camera; ///< normalised frame ([-1, 1]^3 volume)
  /// Transfer function (values in data units), shading, sample distance, LOD policy and blend
  /// mode: may change with every frame without touching the cache or the GPU pool. Unusable
  /// settings are replaced by the last usable ones, with a warning in the frame's statistics.
  afam::FrameSettings Settings;
  // What the renderer is built from: a change builds a new one (new cache, new GPU pool).
  double CacheBudgetMB = 512;
  int Prefetcher = 0; ///< 0 none, 1 linear
  int Device = 0;     ///< 0 auto (GPU when usable), 1 CPU, 2 GPU (CPU when unusable)
  int Threads = 0;
  /// Sort-last rendering over ranks: the renderer draws rank Rank's box of Ranks
  /// (afam::rankBox); the images of all ranks blended in visibility order are the image of one.
  /// Ranks 1: the whole volume.
  int Rank = 0, Ranks = 1;
  /// The GPU the window's OpenGL context runs on (GL_DEVICE_UUID_EXT), when the OpenGL says: the
  /// GPU renderer is built on that CUDA device where it can be (afam::chooseGpuDevice), so that
  /// frames reach the window through CUDA-OpenGL interop. Read when a renderer is built.
  std::optional<afam::DeviceUuid> OpenGLDevice;
  /// Where this frame's image goes and what stops its rays (this frame only):
  /// maxDistance: per-pixel ray length limit from opaque geometry on the host (normalised-frame
  /// distance from the eye, Camera.width * Camera.height floats, row 0 = top); nullptr: none.
  /// deviceRgba: device memory for a frame cast on the GPU (e.g. an OpenGL buffer mapped into
  /// CUDA on GpuStream()); nullptr: the host. deviceDepth: a depth buffer in device memory whose
  /// opaque geometry stops the rays of a frame cast on the GPU (in place of maxDistance).
  afam::FrameTargets Targets;
};

struct vtkAFAMFrameStats
{
  double CachingSeconds = 0, RenderSeconds = 0;
  int64_t CacheHits = 0, CacheMisses = 0, CulledBlocks = 0, VisibleBlocks = 0;
  uint64_t BytesRead = 0;
  /// Bytes of decoded models resident in the RAM cache at the end of the frame (its budget's
  /// measure).
  uint64_t CacheBytes = 0;
  bool UsedGpu = false;
  /// True when this frame built the renderer anew (first frame, a new file, or a change of cache
  /// budget, prefetcher, device or threads): a new RAM cache and a new GPU pool.
  bool RendererBuilt = false;
  /// Models this frame copied to the GPU's pool (0 when every one was resident); -1 on the CPU.
  int64_t GpuModelsUploaded = -1;
  /// The GPU's own times for the frame (CUDA events), in seconds: model upload, ray casting, and
  /// the image's copy back to the host; -1 when the frame was not cast on the GPU.
  double GpuUploadSeconds = -1, GpuKernelSeconds = -1, GpuDownloadSeconds = -1;
  /// True when the image was left at the request's Targets.deviceRgba: the ImageRGBA then holds
  /// the size only (rgba empty).
  bool ImageOnDevice = false;
  /// Pixels the request's Targets.deviceDepth limited; -1 when the frame used none.
  int64_t DeviceDepthLimited = -1;
  /// Why the GPU is not (or not always) used, in words, from the frame that found out (e.g. "no
  /// usable GPU: CUDA driver is missing or too old (cudaErrorInsufficientDriver, 35)"); empty
  /// otherwise. Only set when the GPU was asked for (Device 0 or 2).
  std::vector<std::string> DeviceMessages;
  /// Damaged micro-models: in this frame's selection (drawn from another level), and known in the
  /// file so far; the reports of blocks first found damaged during this frame (each block once).
  int64_t DamagedBlocks = 0, KnownDamagedBlocks = 0;
  /// Blocks drawn from a coarser level because they were still loading (the miss budget).
  int64_t StandInBlocks = 0;
  /// Blocks not drawn at their own level because the budget ran out (the stand-ins, and blocks
  /// with no resident ancestor), and their models' decoded bytes: what the frame left behind.
  int64_t BlocksBehind = 0;
  uint64_t BytesBehind = 0;
  std::vector<std::string> DamageReports;
  /// One sentence per unusable setting of the request: what was asked and what was kept.
  std::vector<std::string> SettingWarnings;
};

class vtkAFAMCoreRenderer
{
public:
  vtkAFAMCoreRenderer();
  ~vtkAFAMCoreRenderer();
  /// Opens (or keeps) the .afam file at a time step (0 for a file of one step); throws
  /// afam::Error with a readable message. Another step of the same run opens anew (its cache,
  /// prefetch thread and GPU pool are built again).
  void Open(const std::string& path, long long step = 0);
  /// Forgets the open file, its renderer (cache, prefetch thread, GPU pool) and damage log.
  void Close();
  const std::string& Path() const
  {
    return this->OpenPath;
  }
  /// World bounds of rank `rank`'s box of `ranks` (afam::rankBox, from the open file alone):
  /// what the rank draws, for ordered compositing. False, bounds untouched, when the box is empty
  /// (more ranks than finest blocks). Throws afam::InvalidArgument for a rank outside
  /// 0 .. ranks-1.
  bool RankBounds(int rank, int ranks, double bounds[6]) const;
  /// afam::contentFingerprint of the open file: what ranks compare to know they draw one file.
  uint64_t Fingerprint() const;
  /// Volume header values the mapper needs for bounds and the normalised frame.
  void Volume(int64_t dims[3], double origin[3], double spacing[3], double range[2]) const;
  /// True when this build has the CUDA renderer (built with nvcc: afam::gpuCasterBuilt).
  static bool HasCuda();
  /// Renders one frame (premultiplied RGBA, row 0 = top). Throws afam::Error; after an
  /// afam::FileChangedError (the file changed on disk) the file is closed, and the next Open reads
  /// it as it is now: no block of the old file is drawn again.
  void Render(const vtkAFAMFrameRequest& request, afam::ImageRGBA& image, vtkAFAMFrameStats& stats);

  /// Builds the renderer `request` needs now, when it needs a new one (the first frame, or after
  /// a change of device, cache, prefetcher or threads; else nothing), so that the frame knows
  /// before it is cast whether it will be cast on the GPU, and its image can go to OpenGL without
  /// the host from the first frame on. The next Render reports the build (RendererBuilt) and the
  /// GPU's set-up notes. Throws what Render's build throws.
  void Prepare(const vtkAFAMFrameRequest& request);
  /// True when Render(request) will cast on the GPU: the current renderer has it (a CUDA build, a
  /// usable GPU, the GPU asked for) and the request keeps that renderer. A frame that builds a
  /// new renderer in Render (without Prepare first) says no.
  bool WillCastOnGpu(const vtkAFAMFrameRequest& request) const;
  /// The cudaStream_t the GPU caster casts on (nullptr without one): where buffers shared with
  /// OpenGL are mapped, so that CUDA's and OpenGL's uses of them are ordered without host waits.
  void* GpuStream() const;

private:
  /// True when Render(request) builds a new renderer (new cache, prefetch thread, GPU pool).
  bool NeedsBuild(const vtkAFAMFrameRequest& request) const;
  /// Builds the renderer for `request` with `settings` (Prepare, Render).
  void Build(const vtkAFAMFrameRequest& request, const afam::FrameSettings& settings);
  struct Internals;
  std::unique_ptr<Internals> Impl;
  std::string OpenPath;
  long long OpenStep = 0;
};

#endif
