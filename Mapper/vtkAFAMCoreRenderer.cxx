// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMCoreRenderer.h"

#include "afam/afam_file.hpp"
#include "afam/renderer.hpp"

#include <cmath>

struct vtkAFAMCoreRenderer::Internals
{
  std::shared_ptr<const afam::AfamFile> File;
  std::unique_ptr<afam::Renderer> Renderer;
  // The settings the Renderer was built with; Core's Renderer takes its options at construction,
  // so a change of transfer function or settings builds a new one (and a new cache).
  afam::RenderOptions Options;
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
    sameTf(a.transferFunction, b.transferFunction);
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

  if (!this->Impl->Renderer || !SameOptions(options, this->Impl->Options))
  {
    this->Impl->Renderer = std::make_unique<afam::Renderer>(this->Impl->File, options);
    this->Impl->Options = options;
  }
  afam::FrameStats frame;
  image = this->Impl->Renderer->renderFrame(request.Camera, frame);
  stats.CachingSeconds = frame.cachingMs * 1e-3;
  stats.RenderSeconds = frame.renderMs * 1e-3;
  stats.CacheHits = static_cast<int64_t>(frame.hits);
  stats.CacheMisses = static_cast<int64_t>(frame.misses);
  stats.CulledBlocks = frame.culled.frustumBlocks + frame.culled.tfBlocks;
  stats.VisibleBlocks = frame.culled.visibleBlocks;
  stats.BytesRead = frame.bytesRead;
  stats.UsedGpu = false; // the CUDA path is not wired into the mapper yet
}
