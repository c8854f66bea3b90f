// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMCoreRenderer.h"

#include "afam/format/afam_file.hpp"
#include "afam/render/renderer.hpp"
#if defined(AFAM_HAVE_CUDA)
#include "afam/cuda/gpu_caster.hpp" // plain C++: the CUDA renderer behind Core's caster hook
#include "afam/cuda/gpu_renderer.hpp" // plain C++: the pool's upload count
#endif

#include <algorithm>
#include <cmath>

struct vtkAFAMCoreRenderer::Internals
{
  std::shared_ptr<const afam::AfamFile> File;
  std::unique_ptr<afam::Renderer> Renderer;
  // What Renderer was built from; per-frame settings are not part of it (setFrameSettings).
  afam::RendererResources Resources;
  bool GpuWanted = false;
  // The last settings that could be drawn: unusable requested settings fall back to these.
  afam::FrameSettings LastGood;
  // GPU: the renderer kept alive while Renderer casts through it, and (once the GPU proved
  // unusable) why, so it is not probed again.
#if defined(AFAM_HAVE_CUDA)
  std::shared_ptr<afam::GpuRenderer> Gpu;
  std::shared_ptr<afam::GpuImageTarget> Target; // the caster's: where GPU frames leave the image
  std::shared_ptr<bool> Failed;                  // the caster's: the GPU failed in a frame
#else
  std::shared_ptr<void> Gpu;
#endif
  float* DeviceImage = nullptr; // SetDeviceImage and SetDeviceDepth, handed to every new caster
  size_t DeviceImageFloats = 0;
  const float* DeviceDepth = nullptr;
  afam::DepthToRay DepthToRay;

  void PassTargets()
  {
#if defined(AFAM_HAVE_CUDA)
    if (this->Target)
    {
      this->Target->deviceRgba = this->DeviceImage;
      this->Target->capacityFloats = this->DeviceImageFloats;
      this->Target->depth.depth = this->DeviceDepth;
      this->Target->depth.toRay = this->DepthToRay;
    }
#endif
  }
  std::string GpuUnusable;
  // The open file's damaged blocks, kept across renderer rebuilds: each is reported once per file.
  std::shared_ptr<afam::DamageLog> Damage;
  std::vector<std::string> Messages; // filled by the GPU caster, drained into each frame's stats

  void DropGpu()
  {
    this->Gpu.reset();
#if defined(AFAM_HAVE_CUDA)
    this->Target.reset();
    this->Failed.reset();
#endif
  }

  int64_t GpuUploads() const
  {
#if defined(AFAM_HAVE_CUDA)
    return this->Gpu ? static_cast<int64_t>(this->Gpu->pool().stats().uploads) : -1;
#else
    return -1;
#endif
  }

  // The CUDA events' times of the frame just cast, when it was cast on the GPU.
  void GpuTimes(vtkAFAMFrameStats& stats) const
  {
#if defined(AFAM_HAVE_CUDA)
    if (this->Gpu && this->Gpu->lastTimes().totalMs > 0)
    {
      const afam::GpuFrameTimes& t = this->Gpu->lastTimes();
      stats.GpuUploadSeconds = t.uploadMs * 1e-3;
      stats.GpuKernelSeconds = t.kernelMs * 1e-3;
      stats.GpuDownloadSeconds = t.downloadMs * 1e-3;
    }
#else
    (void)stats;
#endif
  }

  // After a frame: a GPU that failed (not for memory) is given up for the file's life; the
  // caster already draws on the CPU, and no later renderer probes it again.
  void GiveUpFailedGpu()
  {
#if defined(AFAM_HAVE_CUDA)
    if (this->Gpu && this->Failed && *this->Failed)
    {
      this->GpuUnusable = "the GPU failed during a frame";
      this->Gpu.reset();
      this->Target.reset();
    }
#endif
  }

  void InstallGpu(double budgetMB)
  {
    this->DropGpu();
#if defined(AFAM_HAVE_CUDA)
    if (!this->GpuUnusable.empty())
    {
      return; // known unusable: not probed again (Render reports GpuUnusable)
    }
    std::string notes;
    Internals* self = this; // outlives the caster, which the Renderer below owns
    afam::GpuCaster gpu = afam::installGpuCaster(*this->Renderer,
      static_cast<size_t>(std::max(16.0, budgetMB) * 1e6),
      [self](const std::string& message) { self->Messages.push_back(message); });
    if (gpu)
    {
      this->Gpu = gpu.gpu;
      this->Target = gpu.target;
      this->Failed = gpu.failed;
      this->PassTargets();
      return;
    }
    for (const std::string& m : this->Messages)
    {
      this->GpuUnusable += (this->GpuUnusable.empty() ? "" : "; ") + m;
    }
    this->Messages.clear();
    if (this->GpuUnusable.empty())
    {
      this->GpuUnusable = "the GPU could not be set up";
    }
#else
    (void)budgetMB;
    this->GpuUnusable = "this build has no CUDA renderer (built without nvcc)";
#endif
  }
};

namespace
{
bool SameResources(const afam::RendererResources& a, const afam::RendererResources& b)
{
  return a.threads == b.threads && a.cache.bytes == b.cache.bytes &&
    a.cache.blocks == b.cache.blocks && a.cold == b.cold && a.storageMBps == b.storageMBps &&
    a.prefetch == b.prefetch;
}
}

vtkAFAMCoreRenderer::vtkAFAMCoreRenderer()
  : Impl(new Internals)
{
}

vtkAFAMCoreRenderer::~vtkAFAMCoreRenderer() = default;

void vtkAFAMCoreRenderer::Open(const std::string& path)
{
  if (this->Impl->File && path == this->OpenPath)
  {
    return;
  }
  this->Close();
  this->Impl->File = afam::AfamFile::open(path); // throws afam::Error naming the file
  this->Impl->Damage = std::make_shared<afam::DamageLog>();
  this->OpenPath = path;
}

void vtkAFAMCoreRenderer::Close()
{
  this->Impl->DropGpu();
  this->Impl->Renderer.reset(); // its prefetch thread stops before the file goes
  this->Impl->File.reset();
  this->Impl->Damage.reset();
  this->OpenPath.clear();
}

void vtkAFAMCoreRenderer::Volume(
  int64_t dims[3], double origin[3], double spacing[3], double range[2]) const
{
  const afam::VolumeHeader& h = this->Impl->File->header();
  for (int a = 0; a < 3; ++a)
  {
    dims[a] = h.dims[a];
    origin[a] = h.origin[a];
    spacing[a] = h.spacing[a];
  }
  range[0] = h.valueMin;
  range[1] = h.valueMax;
}

namespace
{
afam::RendererResources ResourcesFor(const vtkAFAMFrameRequest& request)
{
  afam::RendererResources resources;
  resources.threads = request.Threads;
  resources.cache = afam::CacheBudget{ static_cast<uint64_t>(request.CacheBudgetMB * 1e6), 0 };
  resources.prefetch = request.Prefetcher == 1 ? "linear" : "none";
  return resources;
}
}

bool vtkAFAMCoreRenderer::NeedsBuild(const vtkAFAMFrameRequest& request) const
{
  const Internals& m = *this->Impl;
  return !m.Renderer || !SameResources(ResourcesFor(request), m.Resources) ||
    (request.Device != 1) != m.GpuWanted;
}

bool vtkAFAMCoreRenderer::WillCastOnGpu(const vtkAFAMFrameRequest& request) const
{
  return this->Impl->Gpu && !this->NeedsBuild(request);
}

void vtkAFAMCoreRenderer::Render(
  const vtkAFAMFrameRequest& request, afam::ImageRGBA& image, vtkAFAMFrameStats& stats)
{
  const afam::RendererResources resources = ResourcesFor(request);
  const bool wantGpu = request.Device != 1;

  Internals& m = *this->Impl;
  m.Messages.clear();
  const afam::FrameSettings settings =
    afam::acceptFrameSettings(request.Settings, m.LastGood, stats.SettingWarnings);
  stats.RendererBuilt = false;
  if (this->NeedsBuild(request))
  {
    m.DropGpu();
    m.Renderer.reset(); // the old cache and prefetch thread go before the new ones come
    m.Renderer = std::make_unique<afam::Renderer>(m.File, resources, settings, m.Damage);
    m.Resources = resources;
    m.GpuWanted = wantGpu;
    stats.RendererBuilt = true;
    if (wantGpu)
    {
      m.InstallGpu(request.CacheBudgetMB);
    }
  }
  m.LastGood = settings;
  const int64_t uploadsBefore = m.GpuUploads();
  afam::FrameStats frame;
  try
  {
    image = m.Renderer->renderFrame(request.Camera, settings, frame, request.MaxDistance);
  }
  catch (const afam::FileChangedError&)
  {
    this->Close(); // its cache holds blocks of the old file
    throw;
  }
  stats.CachingSeconds = frame.cachingMs * 1e-3;
  stats.RenderSeconds = frame.renderMs * 1e-3;
  stats.CacheHits = static_cast<int64_t>(frame.hits);
  stats.CacheMisses = static_cast<int64_t>(frame.misses);
  stats.CulledBlocks = frame.culled.frustumBlocks + frame.culled.tfBlocks;
  stats.VisibleBlocks = frame.culled.visibleBlocks;
  stats.BytesRead = frame.bytesRead;
  stats.DamagedBlocks = frame.damagedBlocks;
  stats.KnownDamagedBlocks = frame.knownDamagedBlocks;
  stats.DamageReports = std::move(frame.damageReports);
  m.GiveUpFailedGpu();
  stats.UsedGpu = m.Gpu != nullptr;
  stats.GpuModelsUploaded = m.Gpu ? m.GpuUploads() - uploadsBefore : -1;
  m.GpuTimes(stats);
  stats.DeviceMessages.swap(m.Messages); // what happened in this frame (e.g. a pool too small)
  if (wantGpu && !m.Gpu)
  {
    stats.DeviceMessages.push_back(m.GpuUnusable); // every CPU frame says why
  }
}

void* vtkAFAMCoreRenderer::GpuStream() const
{
#if defined(AFAM_HAVE_CUDA)
  return this->Impl->Gpu ? this->Impl->Gpu->pool().stream() : nullptr;
#else
  return nullptr;
#endif
}

void vtkAFAMCoreRenderer::SetDeviceImage(float* deviceRgba, size_t floats)
{
  Internals& m = *this->Impl;
  m.DeviceImage = deviceRgba;
  m.DeviceImageFloats = deviceRgba ? floats : 0;
  m.PassTargets();
}

void vtkAFAMCoreRenderer::SetDeviceDepth(const float* depth, const afam::DepthToRay& toRay)
{
  Internals& m = *this->Impl;
  m.DeviceDepth = depth;
  m.DepthToRay = toRay;
  m.PassTargets();
}

int64_t vtkAFAMCoreRenderer::DeviceDepthLimited() const
{
#if defined(AFAM_HAVE_CUDA)
  return this->Impl->Gpu && this->Impl->Target ? this->Impl->Target->lastDepthLimited : -1;
#else
  return -1;
#endif
}

bool vtkAFAMCoreRenderer::ImageOnDevice() const
{
#if defined(AFAM_HAVE_CUDA)
  return this->Impl->Gpu && this->Impl->Target && this->Impl->Target->lastOnDevice;
#else
  return false;
#endif
}

bool vtkAFAMCoreRenderer::HasCuda()
{
#if defined(AFAM_HAVE_CUDA)
  return true;
#else
  return false;
#endif
}
