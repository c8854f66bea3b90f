// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMCoreRenderer.h"

#ifdef __GLIBC__
#include <malloc.h>
#endif

#include "afam/cuda/render/make_gpu_caster.hpp" // plain C++; a stub in builds without nvcc
#include "afam/format/afam_file.hpp"
#include "afam/ranks/rank_boxes.hpp"
#include "afam/ranks/same_file.hpp"
#include "afam/render/renderer.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

struct vtkAFAMCoreRenderer::Internals
{
  std::shared_ptr<const afam::AfamFile> File;
  std::shared_ptr<const afam::AfamFile> Next; // the step likely drawn next (a run's playback)
  std::unique_ptr<afam::Renderer> Renderer;
  // What Renderer was built from; per-frame settings are not part of it (setFrameSettings).
  afam::RendererResources Resources;
  bool GpuWanted = false;
  // The last settings that could be drawn: unusable requested settings fall back to these.
  afam::FrameSettings LastGood;
  // The Renderer's GPU caster while it casts on the GPU (the Renderer owns it); nullptr: the CPU.
  // Once the GPU proved unusable, why, so it is not probed again.
  afam::FrameCaster* Gpu = nullptr;
  std::string GpuUnusable;
  // The open file's damaged blocks, kept across renderer rebuilds: each is reported once per file.
  std::shared_ptr<afam::DamageLog> Damage;
  std::vector<std::string> Messages; // the GPU's set-up notes, handed to the frame that made it
  bool BuiltUnreported = false;      // built by Prepare: the next Render reports it
  // The last rank box asked for, from the file first opened (a run's later steps keep it, as
  // they keep the renderer): the split is computed once, not every frame.
  struct RankBoxKey
  {
    int Rank = 0, Ranks = 1;
    afam::CellBox Box;
  };
  mutable std::optional<RankBoxKey> LastBox;
  // The open file's fingerprint, computed once a file (ranks compare it at every view update).
  mutable std::weak_ptr<const afam::AfamFile> FingerprintOf;
  mutable uint64_t FingerprintValue = 0;

  const afam::CellBox& BoxOf(int rank, int ranks) const
  {
    if (!this->LastBox || this->LastBox->Rank != rank || this->LastBox->Ranks != ranks)
    {
      this->LastBox = RankBoxKey{ rank, ranks, afam::rankBox(*this->File, rank, ranks) };
    }
    return this->LastBox->Box;
  }

  afam::RendererResources ResourcesFor(const vtkAFAMFrameRequest& request) const
  {
    afam::RendererResources resources;
    resources.threads = request.Threads;
    resources.cache = afam::CacheBudget{ static_cast<uint64_t>(request.CacheBudgetMB * 1e6), 0 };
    resources.prefetch = request.Prefetcher == 1 ? "linear" : "none";
    if (request.Ranks != 1)
    {
      resources.box = this->BoxOf(request.Rank, request.Ranks);
    }
    return resources;
  }

  void InstallGpu(double budgetMB, int threads, const std::optional<afam::DeviceUuid>& openGl)
  {
    this->Gpu = nullptr;
    if (!this->GpuUnusable.empty())
    {
      return; // known unusable: not probed again (Render reports GpuUnusable)
    }
    std::vector<std::string>& notes = this->Messages;
    std::unique_ptr<afam::FrameCaster> gpu = afam::makeGpuCaster(
      static_cast<size_t>(std::max(16.0, budgetMB) * 1e6),
      threads,
      [&notes](const std::string& message) { notes.push_back(message); },
      openGl);
    if (gpu)
    {
      this->Gpu = gpu.get();
      this->Renderer->setCaster(std::move(gpu));
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
  }

  // After a frame: a GPU that failed (not for memory) is given up for the file's life; its caster
  // already draws on the CPU, and no later renderer probes it again.
  void GiveUpFailedGpu()
  {
    if (this->Gpu && !this->Gpu->castsOnGpu())
    {
      this->GpuUnusable = "the GPU failed during a frame";
      this->Gpu = nullptr;
    }
  }
};

namespace
{
bool SameResources(const afam::RendererResources& a, const afam::RendererResources& b)
{
  return a.threads == b.threads && a.cache.bytes == b.cache.bytes &&
    a.cache.blocks == b.cache.blocks && a.cold == b.cold && a.storageMBps == b.storageMBps &&
    a.prefetch == b.prefetch && a.box == b.box;
}
}

vtkAFAMCoreRenderer::vtkAFAMCoreRenderer()
  : Impl(new Internals)
{
}

vtkAFAMCoreRenderer::~vtkAFAMCoreRenderer() = default;

void vtkAFAMCoreRenderer::Open(const std::string& path, long long step)
{
  Internals& m = *this->Impl;
  if (m.File && path == this->OpenPath && step == this->OpenStep)
  {
    return;
  }
  if (m.File && m.Renderer && path == this->OpenPath && this->OpenStep != step)
  {
    // Another step of the same run: the renderer keeps its cache, load threads and GPU pool, so
    // what the steps share is neither read nor decoded nor uploaded again; the step after it in
    // the direction of play is loaded while this one is shown.
    std::shared_ptr<const afam::AfamFile> next =
      (m.Next && m.Next->step() == step) ? m.Next : afam::AfamFile::open(path, step);
    try
    {
      m.Renderer->setStep(next);
    }
    catch (const afam::InvalidArgument&)
    {
      next = nullptr; // not the same file on disk any more: start over below
    }
    if (next)
    {
      const long long ahead = step + (step < this->OpenStep ? -1 : 1);
      m.Next =
        (ahead >= 0 && ahead < next->stepCount()) ? afam::AfamFile::open(path, ahead) : nullptr;
      m.Renderer->setNextStep(m.Next);
      m.File = next;
      this->OpenStep = step;
#ifdef __GLIBC__
      // The decoded models a step change evicts were freed on the load threads, whose heaps keep
      // the pages: hand them back, so that resident memory follows the cache's budget.
      malloc_trim(0);
#endif
      return;
    }
  }
  this->Close();
  this->Impl->File = afam::AfamFile::open(path, step); // throws afam::Error naming the file
  this->Impl->Damage = std::make_shared<afam::DamageLog>();
  this->OpenPath = path;
  this->OpenStep = step;
}

void vtkAFAMCoreRenderer::Close()
{
  this->Impl->Gpu = nullptr;
  this->Impl->Renderer.reset(); // its prefetch thread stops before the file goes
  this->Impl->File.reset();
  this->Impl->Next.reset();
  this->Impl->Damage.reset();
  this->Impl->LastBox.reset();
  this->OpenPath.clear();
}

void vtkAFAMCoreRenderer::Volume(int64_t dims[3],
  double origin[3],
  double spacing[3],
  double range[2]) const
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

uint64_t vtkAFAMCoreRenderer::Fingerprint() const
{
  const Internals& m = *this->Impl;
  if (m.FingerprintOf.lock() != m.File)
  {
    m.FingerprintValue = afam::contentFingerprint(*m.File);
    m.FingerprintOf = m.File;
  }
  return m.FingerprintValue;
}

bool vtkAFAMCoreRenderer::RankBounds(int rank, int ranks, double bounds[6]) const
{
  const afam::AfamFile& file = *this->Impl->File;
  const afam::BlockExtent e = file.partition().samples(this->Impl->BoxOf(rank, ranks));
  if (e.samples[0] < 1)
  {
    return false;
  }
  const afam::VolumeHeader& h = file.header();
  for (int a = 0; a < 3; ++a)
  {
    const double lo = h.origin[a] + h.spacing[a] * static_cast<double>(e.lo[a]);
    const double hi = h.origin[a] + h.spacing[a] * static_cast<double>(e.hi[a]);
    bounds[2 * a] = std::min(lo, hi);
    bounds[2 * a + 1] = std::max(lo, hi);
  }
  return true;
}

bool vtkAFAMCoreRenderer::NeedsBuild(const vtkAFAMFrameRequest& request) const
{
  const Internals& m = *this->Impl;
  return !m.Renderer || !SameResources(m.ResourcesFor(request), m.Resources) ||
    (request.Device != 1) != m.GpuWanted;
}

bool vtkAFAMCoreRenderer::WillCastOnGpu(const vtkAFAMFrameRequest& request) const
{
  return this->Impl->Gpu && !this->NeedsBuild(request);
}

void vtkAFAMCoreRenderer::Build(const vtkAFAMFrameRequest& request,
  const afam::FrameSettings& settings)
{
  Internals& m = *this->Impl;
  const afam::RendererResources resources = m.ResourcesFor(request);
  const bool wantGpu = request.Device != 1;
  m.Gpu = nullptr;
  m.Renderer.reset(); // the old cache, prefetch thread and GPU pool go before the new ones come
  m.Renderer = std::make_unique<afam::Renderer>(m.File, resources, settings, m.Damage);
  m.Resources = resources;
  m.GpuWanted = wantGpu;
  m.BuiltUnreported = true;
  if (wantGpu)
  {
    m.InstallGpu(request.CacheBudgetMB, resources.threads, request.OpenGLDevice);
  }
  // A run: the step after this one is loaded while this one is shown (playback goes forward
  // first; Open() follows the direction of play from the first step change on).
  const long long ahead =
    this->OpenStep + 1 < m.File->stepCount() ? this->OpenStep + 1 : this->OpenStep - 1;
  if (!m.Next && ahead >= 0 && ahead != this->OpenStep)
  {
    m.Next = afam::AfamFile::open(this->OpenPath, ahead);
  }
  m.Renderer->setNextStep(m.Next);
}

void vtkAFAMCoreRenderer::Prepare(const vtkAFAMFrameRequest& request)
{
  Internals& m = *this->Impl;
  if (!m.File || !this->NeedsBuild(request))
  {
    return;
  }
  if (!m.BuiltUnreported)
  {
    m.Messages.clear();
  }
  std::vector<std::string> unused; // Render reports the settings' warnings
  this->Build(request, afam::acceptFrameSettings(request.Settings, m.LastGood, unused));
}

void vtkAFAMCoreRenderer::Render(const vtkAFAMFrameRequest& request,
  afam::ImageRGBA& image,
  vtkAFAMFrameStats& stats)
{
  const bool wantGpu = request.Device != 1;

  Internals& m = *this->Impl;
  if (!m.BuiltUnreported)
  {
    m.Messages.clear(); // else they are the set-up notes of the build Prepare made
  }
  const afam::FrameSettings settings =
    afam::acceptFrameSettings(request.Settings, m.LastGood, stats.SettingWarnings);
  if (this->NeedsBuild(request))
  {
    this->Build(request, settings);
  }
  stats.RendererBuilt = m.BuiltUnreported;
  m.BuiltUnreported = false;
  m.LastGood = settings;
  afam::FrameStats frame;
  try
  {
    image = m.Renderer->renderFrame(request.Camera, settings, frame, request.Targets);
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
  stats.CulledBlocks =
    frame.culled.frustumBlocks + frame.culled.tfBlocks + frame.culled.emptyBlocks;
  stats.VisibleBlocks = frame.culled.visibleBlocks;
  stats.BytesRead = frame.bytesRead;
  stats.CacheBytes = frame.cacheBytes;
  stats.DamagedBlocks = frame.damagedBlocks;
  stats.KnownDamagedBlocks = frame.knownDamagedBlocks;
  stats.StandInBlocks = frame.standInBlocks;
  stats.BlocksBehind = frame.blocksBehind;
  stats.BytesBehind = frame.bytesBehind;
  stats.DamageReports = std::move(frame.damageReports);
  m.GiveUpFailedGpu();
  const afam::CastResult& cast = frame.cast;
  stats.UsedGpu = m.Gpu != nullptr;
  stats.GpuModelsUploaded = m.Gpu ? cast.modelsUploaded : -1;
  if (cast.onGpu && cast.gpuUploadMs >= 0) // the CUDA events' times
  {
    stats.GpuUploadSeconds = cast.gpuUploadMs * 1e-3;
    stats.GpuKernelSeconds = cast.gpuKernelMs * 1e-3;
    stats.GpuDownloadSeconds = cast.gpuDownloadMs * 1e-3;
  }
  stats.ImageOnDevice = cast.imageOnDevice;
  stats.DeviceDepthLimited = m.Gpu ? cast.depthLimitedPixels : -1;
  // What happened in this frame: the GPU's set-up, then the caster's (e.g. a pool too small).
  stats.DeviceMessages.swap(m.Messages);
  stats.DeviceMessages.insert(
    stats.DeviceMessages.end(), cast.messages.begin(), cast.messages.end());
  if (wantGpu && !m.Gpu)
  {
    stats.DeviceMessages.push_back(m.GpuUnusable); // every CPU frame says why
  }
}

void* vtkAFAMCoreRenderer::GpuStream() const
{
  return this->Impl->Gpu ? this->Impl->Gpu->deviceStream() : nullptr;
}

bool vtkAFAMCoreRenderer::HasCuda()
{
  return afam::gpuCasterBuilt();
}
