// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMCoreRenderer.h"

#include "afam/afam_file.hpp"
#include "afam/renderer.hpp"
#if defined(AFAM_HAVE_CUDA)
#include "afam/cuda/gpu_caster.hpp" // plain C++: the CUDA renderer behind Core's caster hook
#endif

#include <algorithm>
#include <cmath>

struct vtkAFAMCoreRenderer::Internals
{
  std::shared_ptr<const afam::AfamFile> File;
  std::unique_ptr<afam::Renderer> Renderer;
  // The settings the Renderer was built with; Core's Renderer takes its options at construction,
  // so a change of transfer function or settings builds a new one (and a new cache).
  afam::RenderOptions Options;
  // GPU: the renderer kept alive while Renderer casts through it, whether it was asked for with
  // the current Renderer, and (once the GPU proved unusable) why, so it is not probed again.
  std::shared_ptr<void> Gpu;
  bool GpuWanted = false;
  std::string GpuUnusable;
  std::vector<std::string> Messages; // filled by the GPU caster, drained into each frame's stats

  void InstallGpu(double budgetMB)
  {
    this->Gpu.reset();
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
bool SameOptions(const afam::RenderOptions& a, const afam::RenderOptions& b)
{
  auto sameTf = [](const afam::TransferFunction& x, const afam::TransferFunction& y) {
    if (x.colors.size() != y.colors.size() || x.opacities.size() != y.opacities.size() ||
      x.referenceDistance != y.referenceDistance)
    {
      return false;
    }
    for (size_t i = 0; i < x.colors.size(); ++i)
    {
      const auto &p = x.colors[i], &q = y.colors[i];
      if (p.value != q.value || p.r != q.r || p.g != q.g || p.b != q.b)
      {
        return false;
      }
    }
    for (size_t i = 0; i < x.opacities.size(); ++i)
    {
      if (x.opacities[i].value != y.opacities[i].value ||
        x.opacities[i].alpha != y.opacities[i].alpha)
      {
        return false;
      }
    }
    return true;
  };
  return a.threads == b.threads && a.sampleDistance == b.sampleDistance &&
    a.shading == b.shading && a.lod.policy == b.lod.policy && a.cache.bytes == b.cache.bytes &&
    a.prefetch == b.prefetch && a.hasTransferFunction == b.hasTransferFunction &&
    a.blendMode == b.blendMode && sameTf(a.transferFunction, b.transferFunction);
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
  this->Impl->Renderer.reset();
  this->Impl->File.reset();
  this->OpenPath.clear();
  this->Impl->File = afam::AfamFile::open(path); // throws afam::Error naming the file
  this->OpenPath = path;
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

void vtkAFAMCoreRenderer::Render(
  const vtkAFAMFrameRequest& request, afam::ImageRGBA& image, vtkAFAMFrameStats& stats)
{
  afam::RenderOptions options;
  options.threads = request.Threads;
  if (request.SampleDistance > 0)
  {
    options.sampleDistance = static_cast<float>(request.SampleDistance);
  }
  options.shading = request.Shading;
  options.lod.policy = request.LodPolicy == 1 ? afam::LodPolicy::Screen : afam::LodPolicy::Distance;
  options.cache = afam::CacheBudget{ static_cast<uint64_t>(request.CacheBudgetMB * 1e6), 0 };
  options.prefetch = request.Prefetcher == 1 ? "linear" : "none";
  options.hasTransferFunction =
    !request.Transfer.colors.empty() && !request.Transfer.opacities.empty();
  options.transferFunction = request.Transfer;
  options.blendMode = request.BlendMode;

  const bool wantGpu = request.Device != 1;
  Internals& m = *this->Impl;
  m.Messages.clear();
  if (!m.Renderer || !SameOptions(options, m.Options) || wantGpu != m.GpuWanted)
  {
    m.Gpu.reset();
    m.Renderer = std::make_unique<afam::Renderer>(m.File, options);
    m.Options = options;
    m.GpuWanted = wantGpu;
    if (wantGpu)
    {
      m.InstallGpu(request.CacheBudgetMB);
    }
  }
  afam::FrameStats frame;
  image = m.Renderer->renderFrame(request.Camera, frame, request.MaxDistance);
  stats.CachingSeconds = frame.cachingMs * 1e-3;
  stats.RenderSeconds = frame.renderMs * 1e-3;
  stats.CacheHits = static_cast<int64_t>(frame.hits);
  stats.CacheMisses = static_cast<int64_t>(frame.misses);
  stats.CulledBlocks = frame.culled.frustumBlocks + frame.culled.tfBlocks;
  stats.VisibleBlocks = frame.culled.visibleBlocks;
  stats.BytesRead = frame.bytesRead;
  stats.UsedGpu = m.Gpu != nullptr;
  stats.DeviceMessages.swap(m.Messages); // what happened in this frame (e.g. a pool too small)
  if (wantGpu && !m.Gpu)
  {
    stats.DeviceMessages.push_back(m.GpuUnusable); // every CPU frame says why
  }
}

bool vtkAFAMCoreRenderer::HasCuda()
{
#if defined(AFAM_HAVE_CUDA)
  return true;
#else
  return false;
#endif
}
