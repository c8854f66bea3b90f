// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMVolumeMapper.h"

#include "vtkAFAMCoreRenderer.h"
#include "vtkAFAMCudaGLBuffer.h"
#include "vtkAFAMImageDraw.h"
#include "vtkAFAMModelTree.h"
#include "vtkAFAMTransferFunctionTable.h"

#include "afam/format/file_identity.hpp"
#include "afam/scene/view_mapping.hpp"

#include "vtkCamera.h"
#include "vtkInformation.h"
#include "vtkLogger.h"
#include "vtkMath.h"
#include "vtkMatrix4x4.h"
#include "vtkMultiBlockDataSet.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkOpenGLRenderWindow.h"
#include "vtkOpenGLState.h"
#include "vtkProp.h"
#include "vtkPropCollection.h"
#include "vtkRenderer.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"
#include "vtk_glew.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <vector>

vtkStandardNewMacro(vtkAFAMVolumeMapper);

vtkAFAMVolumeMapper::vtkAFAMVolumeMapper()
  : Core(new vtkAFAMCoreRenderer)
  , Draw(new vtkAFAMImageDraw)
  , DepthBuffer(new vtkAFAMCudaGLBuffer(vtkAFAMCudaGLBuffer::CUDA_READS))
{
  // vtkVolume skips a mapper that has no input data object, so a mapper given only FileName
  // would never be asked to render: an empty multiblock stands in until an input is connected.
  vtkNew<vtkMultiBlockDataSet> placeholder;
  this->SetInputDataObject(0, placeholder);
}

vtkAFAMVolumeMapper::~vtkAFAMVolumeMapper()
{
  this->SetFileName(nullptr);
}

int vtkAFAMVolumeMapper::FillInputPortInformation(int, vtkInformation* info)
{
  // The input only names the file (field data of the reader's/encoder's multiblock); optional,
  // since FileName can be set directly.
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkDataObject");
  info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
  return 1;
}

std::string vtkAFAMVolumeMapper::ResolveFileName()
{
  this->ResolvedStep = this->TimeStep;
  if (this->FileName && *this->FileName)
  {
    return this->FileName;
  }
  if (this->GetNumberOfInputConnections(0) > 0)
  {
    this->UpdateInformation();
    this->GetInputAlgorithm()->Update();
    auto* tree = vtkMultiBlockDataSet::SafeDownCast(this->GetInputDataObject(0, 0));
    this->ResolvedStep = vtkAFAMModelTree::Step(tree); // the step the pipeline's time chose
    return vtkAFAMModelTree::FileName(tree);
  }
  return {};
}

bool vtkAFAMVolumeMapper::EnsureOpen()
{
  const std::string path = this->ResolveFileName();
  if (path.empty())
  {
    vtkErrorMacro(
      << "No .afam file: set FileName or connect the output of vtkAFAMReader/vtkAFAMEncoder.");
    return false;
  }
  try
  {
    this->Core->Open(path, this->ResolvedStep);
  }
  catch (const std::exception& e)
  {
    // Each frame tries again (the file may be repaired), but says what is wrong once until that
    // changes, not once per frame.
    if (this->LastOpenError != e.what())
    {
      vtkErrorMacro(<< this->RankPrefix() << e.what());
    }
    this->LastOpenError = e.what();
    return false;
  }
  this->LastOpenError.clear();
  return true;
}

void vtkAFAMVolumeMapper::SetRenderDevice(int device)
{
  device = std::min(std::max(device, static_cast<int>(DEVICE_AUTO)), static_cast<int>(DEVICE_GPU));
  if (device != this->RenderDevice)
  {
    this->RenderDevice = device;
    this->WarnedDevice = false; // a new choice reports its fallback again, once
    this->Modified();
  }
}

std::string vtkAFAMVolumeMapper::RankPrefix() const
{
  return this->NumberOfRanks > 1
    ? "rank " + std::to_string(this->Rank) + " of " + std::to_string(this->NumberOfRanks) + ": "
    : std::string();
}

void vtkAFAMVolumeMapper::SetRank(int rank, int ranks)
{
  if (rank != this->Rank || ranks != this->NumberOfRanks)
  {
    this->Rank = rank;
    this->NumberOfRanks = ranks;
    this->Modified();
  }
}

bool vtkAFAMVolumeMapper::GetRankBounds(double bounds[6])
{
  if (!vtkMath::AreBoundsInitialized(this->GetBounds())) // opens the file when it can
  {
    return false;
  }
  try
  {
    return this->Core->RankBounds(this->Rank, this->NumberOfRanks, bounds);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< this->RankPrefix() << e.what());
    return false;
  }
}

vtkTypeUInt64 vtkAFAMVolumeMapper::GetFileFingerprint()
{
  return this->EnsureOpen() ? this->Core->Fingerprint() : 0; // EnsureOpen says why not
}

bool vtkAFAMVolumeMapper::HasCudaRenderer()
{
  return vtkAFAMCoreRenderer::HasCuda();
}

void vtkAFAMVolumeMapper::ReleaseGraphicsResources(vtkWindow* window)
{
  this->Draw->ReleaseGraphicsResources(window);
  this->DepthBuffer->Free();
}

double* vtkAFAMVolumeMapper::GetBounds()
{
  vtkMath::UninitializeBounds(this->Bounds);
  // Opens the file when none is open, or when FileName names another (the pipeline's input is
  // resolved only when nothing is open: it updates the input).
  const bool renamed = this->FileName && *this->FileName && this->Core->Path() != this->FileName;
  if (this->Core->Path().empty() || renamed)
  {
    const std::string path = this->ResolveFileName();
    if (path.empty())
    {
      return this->Bounds;
    }
    try
    {
      this->Core->Open(path, this->ResolvedStep);
    }
    catch (const std::exception&)
    {
      return this->Bounds; // reported by Render
    }
  }
  int64_t dims[3];
  double origin[3], spacing[3], range[2];
  this->Core->Volume(dims, origin, spacing, range);
  for (int a = 0; a < 3; ++a)
  {
    const double end = origin[a] + spacing[a] * static_cast<double>(dims[a] - 1);
    this->Bounds[2 * a] = std::min(origin[a], end);
    this->Bounds[2 * a + 1] = std::max(origin[a], end);
  }
  return this->Bounds;
}

// What one frame's steps share: the viewport (tile) size, the size of the cast image, the world
// -> normalised frame map, and the opaque geometry's ray lengths.
struct vtkAFAMVolumeMapper::Frame
{
  int Width = 0, Height = 0;         // the renderer's part of the current tile
  int CastWidth = 0, CastHeight = 0; // the image Core casts (smaller for interactive frames)
  double Scale = 1;
  bool Interactive = false; // the window asks for more than one frame a second
  afam::FrameMap Map;
  std::vector<float> Limits;
  bool DepthOnGpu = false; // the depth buffer may go to CUDA (the image does)
  bool Idle = false;       // this rank draws nothing this frame (ReadFrameSettings)
  vtkAFAMFrameRequest Request;
};

bool vtkAFAMVolumeMapper::RenderCore(Frame& frame, afam::ImageRGBA& image, vtkAFAMFrameStats& stats)
{
  try
  {
    this->Core->Render(frame.Request, image, stats);
    return true;
  }
  catch (const afam::FileChangedError& changed)
  {
    // Another process rewrote, truncated or replaced the file. Core closed it (nothing of the old
    // file is drawn again); this frame opens it as it is now, with one message either way.
    try
    {
      const std::string path = this->ResolveFileName();
      this->Core->Open(path, this->ResolvedStep);
      this->LastOpenError.clear();
    }
    catch (const std::exception& e)
    {
      vtkErrorMacro(<< this->RankPrefix() << changed.what()
                    << "; opening it again failed: " << e.what());
      this->LastOpenError = e.what(); // not repeated by the next frames' EnsureOpen
      return false;
    }
    vtkWarningMacro(<< changed.what() << "; opened again, its new contents are drawn");
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< this->RankPrefix() << e.what());
    return false;
  }
  try
  {
    this->Core->Render(frame.Request, image, stats);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< this->RankPrefix() << e.what());
    return false;
  }
  return true;
}

void vtkAFAMVolumeMapper::Render(vtkRenderer* ren, vtkVolume* vol)
{
  const auto start = std::chrono::steady_clock::now();
  Frame frame;
  if (!this->EnsureOpen() || !this->PlanImage(ren, vol, frame) || !this->MapCamera(ren, vol, frame))
  {
    return;
  }
  this->ReadFrameSettings(vol->GetProperty(), frame);
  if (frame.Idle)
  {
    this->RecordStatistics(frame, vtkAFAMFrameStats{});
    return;
  }
  auto* renWin = vtkOpenGLRenderWindow::SafeDownCast(ren->GetRenderWindow());
  // Frames cast on the GPU go straight into an OpenGL buffer when CUDA can write into one, and
  // then take the depth buffer the same way (ReadDepthLimits). A frame that needs a new renderer
  // (the first, or after a change of device or cache) builds it first, so that it goes that way
  // too (in ParaView, the image of OpenDataFile + Show + SaveScreenshot is such a frame).
  if (renWin != this->UuidWindow)
  {
    this->UuidWindow = renWin; // asked once a window: a renderer built later takes it
    this->OpenGLDevice = vtkAFAMCudaGLBuffer::ContextDeviceUuid();
  }
  frame.Request.OpenGLDevice = this->OpenGLDevice;
  if (this->GpuImageInterop)
  {
    try
    {
      this->Core->Prepare(frame.Request);
    }
    catch (const std::exception&)
    {
      // RenderCore builds it again and reports why it cannot
    }
  }
  void* const mappedStream = this->Core->GpuStream();
  size_t deviceFloats = 0;
  float* deviceImage = this->GpuImageInterop && this->Core->WillCastOnGpu(frame.Request)
    ? this->Draw->MapDeviceImage(
        frame.CastWidth, frame.CastHeight, this->Core->GpuStream(), deviceFloats)
    : nullptr;
  frame.Request.Targets.deviceRgba = deviceImage;
  frame.Request.Targets.deviceRgbaFloats = deviceImage ? deviceFloats : 0;
  frame.DepthOnGpu = deviceImage != nullptr;
  const auto depthStart = std::chrono::steady_clock::now();
  const bool depthRead = this->ReadDepthLimits(ren, frame);
  const auto depthEnd = depthRead ? std::chrono::steady_clock::now() : depthStart;
  afam::ImageRGBA image;
  vtkAFAMFrameStats stats;
  const bool cast = this->RenderCore(frame, image, stats);
  if (this->Core->GpuStream() != mappedStream)
  {
    // The renderer was rebuilt within this frame (the file changed on disk and was opened again):
    // the stream the buffers were mapped on went with the old one.
    this->DepthBuffer->StreamEnded();
    this->Draw->DeviceImageStreamEnded();
  }
  this->DepthBuffer->Unmap();
  if (frame.DepthOnGpu && stats.DeviceDepthLimited >= 0)
  {
    this->LastDepthLimitedPixels = stats.DeviceDepthLimited;
  }
  this->LastImageOnDevice = cast && stats.ImageOnDevice;
  if (!this->LastImageOnDevice)
  {
    this->Draw->UnmapDeviceImage();
  }
  if (!cast)
  {
    return;
  }
  if (image.width != frame.CastWidth || image.height != frame.CastHeight ||
    (!this->LastImageOnDevice &&
      image.rgba.size() != 4 * static_cast<size_t>(image.width) * image.height))
  {
    vtkErrorMacro(<< "Core returned a " << image.width << "x" << image.height << " image for a "
                  << frame.CastWidth << "x" << frame.CastHeight << " request");
    return;
  }
  const auto drawStart = std::chrono::steady_clock::now();
  if (this->LastImageOnDevice)
  {
    this->Draw->DrawDeviceImage(renWin, image.width, image.height);
  }
  else
  {
    this->Draw->DrawHostImage(renWin, image.width, image.height, image.rgba.data());
  }
  const auto end = std::chrono::steady_clock::now();
  this->LastInteropProblem = this->Draw->Problem();
  // Frames cast on the GPU but drawn through the host (an OpenGL that shares no buffers with
  // CUDA, as Mesa's): said once per problem, as information (the image is right, only slower).
  if (stats.UsedGpu && !this->LastInteropProblem.empty() &&
    this->LastInteropProblem != this->ReportedInteropProblem)
  {
    this->ReportedInteropProblem = this->LastInteropProblem;
    vtkLog(INFO,
      "Adaptive-FAM: frames cast on the GPU reach the window through the host (no CUDA-OpenGL "
      "interop here): "
        << this->LastInteropProblem);
  }
  this->RecordStatistics(frame, stats);
  this->LastDepthReadTime = std::chrono::duration<double>(depthEnd - depthStart).count();
  this->LastDrawTime = std::chrono::duration<double>(end - drawStart).count();
  this->LastTotalTime = std::chrono::duration<double>(end - start).count();
}

bool vtkAFAMVolumeMapper::PlanImage(vtkRenderer* ren, vtkVolume* vol, Frame& frame)
{
  auto* renWin = vtkOpenGLRenderWindow::SafeDownCast(ren->GetRenderWindow());
  vtkCamera* cam = ren->GetActiveCamera();
  if (!renWin || !cam || !vol->GetProperty())
  {
    vtkErrorMacro(<< "needs an OpenGL render window, an active camera and a volume property");
    return false;
  }
  if (cam->GetUseOffAxisProjection())
  {
    vtkErrorMacro(<< "off-axis (head-tracked) projection is not supported by the Adaptive-FAM "
                     "renderer; nothing is drawn");
    return false;
  }
  // The image is the renderer's part of the current tile: with a magnified screenshot VTK renders
  // tiles of the window's size, narrowing the view angle (or parallel scale) and moving the
  // camera's WindowCenter per tile.
  int tileX = 0, tileY = 0;
  ren->GetTiledSizeAndOrigin(&frame.Width, &frame.Height, &tileX, &tileY);
  if (frame.Width < 1 || frame.Height < 1)
  {
    return false;
  }
  // Interactive frames: a smaller image that fits the allotted time (see AutoAdjustImageScale).
  const double rate = renWin->GetDesiredUpdateRate();
  frame.Interactive = rate > 1.0;
  if (this->AutoAdjustImageScale && rate > 1.0 && this->SecondsPerPixel > 0)
  {
    const double allotted = vol->GetAllocatedRenderTime();
    const double budget = allotted > 0 ? std::min(allotted, 1.0 / rate) : 1.0 / rate;
    frame.Scale = std::sqrt(budget / (this->SecondsPerPixel * frame.Width * frame.Height));
    frame.Scale = std::max(this->MinimumImageScale, std::min(1.0, frame.Scale));
  }
  frame.CastWidth = std::max(1, static_cast<int>(std::lround(frame.Width * frame.Scale)));
  frame.CastHeight = std::max(1, static_cast<int>(std::lround(frame.Height * frame.Scale)));
  return true;
}

bool vtkAFAMVolumeMapper::MapCamera(vtkRenderer* ren, vtkVolume* vol, Frame& frame)
{
  // World -> normalised frame: the inverse of the vtkVolume's matrix takes the world to the data,
  // then the data box maps to [-1, 1]^3, each axis on its own (paper).
  vtkMatrix4x4* toWorld = vol->GetMatrix();
  const double det = toWorld->Determinant();
  if (!(std::abs(det) > 1e-300) || !std::isfinite(det))
  {
    vtkErrorMacro(<< "the volume's transform is singular (a zero Scale?) or not finite; "
                     "nothing is drawn");
    return false;
  }
  vtkNew<vtkMatrix4x4> toData;
  vtkMatrix4x4::Invert(toWorld, toData);
  std::array<double, 16> worldToData;
  std::copy_n(toData->GetData(), 16, worldToData.begin());
  const double* b = this->GetBounds();
  frame.Map = afam::frameMapFromWorld(worldToData, { b[0], b[2], b[4] }, { b[1], b[3], b[5] });

  vtkCamera* cam = ren->GetActiveCamera();
  afam::ViewFrustum view;
  cam->GetPosition(view.position.data());
  cam->GetFocalPoint(view.focalPoint.data());
  cam->GetViewUp(view.viewUp.data());
  view.parallel = cam->GetParallelProjection() != 0;
  view.viewAngleDeg = cam->GetViewAngle();
  view.horizontalViewAngle = cam->GetUseHorizontalViewAngle() != 0;
  view.parallelScale = cam->GetParallelScale();
  view.aspect = ren->GetTiledAspectRatio();
  view.windowCenter = { cam->GetWindowCenter()[0], cam->GetWindowCenter()[1] };
  view.nearClip = cam->GetClippingRange()[0];
  try
  {
    frame.Request.Camera =
      afam::cameraFromFrustum(view, frame.Map, frame.CastWidth, frame.CastHeight);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return false;
  }
  return true;
}

void vtkAFAMVolumeMapper::ReadFrameSettings(vtkVolumeProperty* property, Frame& frame)
{
  vtkAFAMFrameRequest& request = frame.Request;
  afam::FrameSettings& settings = request.Settings;
  // Transfer functions and shading from the volume property (component 0), world lengths to
  // normalised-frame lengths (Camera::mapped's lengthUnit keeps steps and opacities right in
  // every direction when the map stretches axes differently). Core checks what comes out and
  // keeps the last usable settings, with a warning (RecordStatistics).
  settings.hasTransferFunction = true;
  afam::TransferFunction& tf = settings.transferFunction;
  int64_t dims[3];
  double origin[3], spacing[3], range[2];
  this->Core->Volume(dims, origin, spacing, range);
  vtkAFAMSampleTransferFunctions(property, range[0], range[1], this->DrawMissingValues, tf);
  settings.tfTableSize = vtkAFAMTransferFunctionTableSize;
  const double lengthUnit = request.Camera.lengthUnit;
  const double unitDistance = property->GetScalarOpacityUnitDistance(0);
  tf.referenceDistance = unitDistance / lengthUnit;
  settings.shading = property->GetShade(0) != 0;
  settings.jitter = this->UseJittering;
  const double sampleWorld =
    this->SampleDistance > 0 ? this->SampleDistance : this->DefaultSampleDistance(spacing);
  settings.sampleDistance = static_cast<float>(sampleWorld / lengthUnit);
  settings.lod.policy =
    this->LodPolicy == LOD_SCREEN_SPACE ? afam::LodPolicy::Screen : afam::LodPolicy::Distance;
  settings.lod.pixelBudget = this->LodPixelBudget;
  settings.missBudgetMs = frame.Interactive ? this->InteractiveMissBudget : -1;
  // Composite, maximum, minimum and average intensity (VTK's numbering); other modes are drawn
  // composite, with one warning.
  const int blend = this->GetBlendMode();
  settings.blendMode = blend >= COMPOSITE_BLEND && blend <= AVERAGE_INTENSITY_BLEND ? blend : 0;
  if (settings.blendMode != blend && !this->WarnedBlendMode)
  {
    this->WarnedBlendMode = true;
    vtkWarningMacro(<< "blend mode " << blend
                    << " is not supported by the Adaptive-FAM renderer (composite, maximum, "
                       "minimum and average intensity are); drawing it composite");
  }
  request.CacheBudgetMB = this->CacheBudgetMB;
  request.Prefetcher = this->Prefetcher;
  request.Device = this->RenderDevice;
  request.Threads = this->NumberOfThreads;
  // Ordered compositing blends the ranks' images "over", composite blending's own operator; the
  // maximum, minimum and average of several images are not blended that way, so rank 0 draws
  // those whole and the other ranks nothing (frame.Idle).
  const bool shared = settings.blendMode == COMPOSITE_BLEND;
  request.Rank = shared ? this->Rank : 0;
  request.Ranks = shared ? this->NumberOfRanks : 1;
  frame.Idle = !shared && this->Rank != 0;
}

double vtkAFAMVolumeMapper::DefaultSampleDistance(const double spacing[3])
{
  double finest = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a)
  {
    if (spacing[a] > 0)
    {
      finest = std::min(finest, std::abs(spacing[a]));
    }
  }
  return std::isfinite(finest) ? finest : 1.0;
}

namespace
{
// Whether anything in `ren` but volumes may have written depth: a visible prop that is no volume
// and does not say it lacks opaque geometry (vtkProp's default says it has some). Without one the
// z-buffer holds the far plane only, and reading it back would limit no ray.
bool MayHaveOpaqueGeometry(vtkRenderer* ren)
{
  vtkPropCollection* props = ren->GetViewProps();
  vtkCollectionSimpleIterator it;
  props->InitTraversal(it);
  while (vtkProp* prop = props->GetNextProp(it))
  {
    if (prop->GetVisibility() && !vtkVolume::SafeDownCast(prop) && prop->HasOpaqueGeometry())
    {
      return true;
    }
  }
  return false;
}
}

bool vtkAFAMVolumeMapper::ReadDepthLimits(vtkRenderer* ren, Frame& frame)
{
  // Opaque geometry drawn so far stops the rays (see the class documentation).
  this->LastDepthLimitedPixels = 0;
  if (!this->DepthCompositing || !MayHaveOpaqueGeometry(ren))
  {
    return false;
  }
  int x0 = 0, y0 = 0, w = 0, h = 0;
  ren->GetTiledSizeAndOrigin(&w, &h, &x0, &y0);
  vtkNew<vtkMatrix4x4> inverse;
  vtkMatrix4x4::Invert(ren->GetActiveCamera()->GetCompositeProjectionTransformMatrix(
                         ren->GetTiledAspectRatio(), -1, 1),
    inverse);
  std::array<double, 16> ndcToWorld;
  std::copy_n(inverse->GetData(), 16, ndcToWorld.begin());
  if (frame.DepthOnGpu && this->ReadDepthOnGpu(ren, x0, y0, w, h, ndcToWorld, frame))
  {
    return true;
  }
  std::vector<float> depth(static_cast<size_t>(w) * static_cast<size_t>(h));
  if (ren->GetRenderWindow()->GetZbufferData(x0, y0, x0 + w - 1, y0 + h - 1, depth.data()) !=
    VTK_OK)
  {
    vtkWarningMacro(<< "cannot read the z-buffer; the volume is blended over opaque geometry");
    return true;
  }
  const int64_t limited = afam::rayLengthsFromDepth(
    depth.data(), w, h, ndcToWorld, frame.Map, frame.Request.Camera, frame.Limits);
  if (limited > 0)
  {
    frame.Request.Targets.maxDistance = frame.Limits.data();
    this->LastDepthLimitedPixels = limited;
  }
  return true;
}

bool vtkAFAMVolumeMapper::ReadDepthOnGpu(vtkRenderer* ren,
  int x0,
  int y0,
  int w,
  int h,
  const std::array<double, 16>& ndcToWorld,
  Frame& frame)
{
  // The z-buffer is packed into a buffer that CUDA then reads: glReadPixels with a pixel-pack
  // buffer bound writes into it (VTK's GetZbufferData binds the right framebuffer and resolves
  // multisampling; its pointer is then an offset into the buffer).
  if (!this->DepthBuffer->Reserve(static_cast<size_t>(w) * static_cast<size_t>(h) * sizeof(float)))
  {
    return false;
  }
  glBindBuffer(GL_PIXEL_PACK_BUFFER, this->DepthBuffer->Name());
  const int read = ren->GetRenderWindow()->GetZbufferData(
    x0, y0, x0 + w - 1, y0 + h - 1, static_cast<float*>(nullptr));
  glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
  const float* depth = read == VTK_OK
    ? static_cast<const float*>(this->DepthBuffer->Map(this->Core->GpuStream()))
    : nullptr;
  if (!depth)
  {
    return false;
  }
  try
  {
    frame.Request.Targets.deviceDepth = afam::DeviceDepth{ depth,
      afam::depthToRay(w, h, ndcToWorld, frame.Map, frame.Request.Camera) };
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    this->DepthBuffer->Unmap();
    return false;
  }
  return true;
}

namespace
{
std::string JoinSentences(const std::vector<std::string>& sentences)
{
  std::string all;
  for (const std::string& s : sentences)
  {
    all += (all.empty() ? "" : "; ") + s;
  }
  return all;
}
}

void vtkAFAMVolumeMapper::RecordStatistics(const Frame& frame, const vtkAFAMFrameStats& stats)
{
  // Time per cast pixel, for the next interactive frame's scale: the latest still frame sets it,
  // interactive frames blend in (they are smaller, so fixed costs weigh more there).
  const double frameSeconds = stats.RenderSeconds + stats.CachingSeconds;
  const double perPixel = frameSeconds / (static_cast<double>(frame.CastWidth) * frame.CastHeight);
  this->SecondsPerPixel = (this->SecondsPerPixel > 0 && frame.Scale < 1.0)
    ? 0.5 * (this->SecondsPerPixel + perPixel)
    : perPixel;
  this->LastImageScale = static_cast<double>(frame.CastWidth) / frame.Width;
  this->LastCachingTime = stats.CachingSeconds;
  this->LastRenderTime = stats.RenderSeconds;
  this->LastCacheHits = stats.CacheHits;
  this->LastCacheMisses = stats.CacheMisses;
  this->LastCulledBlocks = stats.CulledBlocks;
  this->LastVisibleBlocks = stats.VisibleBlocks;
  this->LastBytesRead = static_cast<vtkTypeInt64>(stats.BytesRead);
  this->LastCacheBytes = static_cast<vtkTypeInt64>(stats.CacheBytes);
  this->LastDamagedBlocks = stats.DamagedBlocks;
  this->KnownDamagedBlocks = stats.KnownDamagedBlocks;
  this->LastStandInBlocks = stats.StandInBlocks;
  this->LastBlocksBehind = stats.BlocksBehind;
  this->LastBytesBehind = static_cast<vtkTypeInt64>(stats.BytesBehind);
  // Blocks first found damaged in this frame: one warning (Core reads and reports each block only
  // once per file), the first few in full so that a truncated file does not flood the window.
  if (!stats.DamageReports.empty())
  {
    const size_t shown = std::min<size_t>(stats.DamageReports.size(), 4);
    std::string text;
    for (size_t i = 0; i < shown; ++i)
    {
      text += (i ? "\n" : "") + stats.DamageReports[i];
    }
    if (stats.DamageReports.size() > shown)
    {
      text += "\n... and " + std::to_string(stats.DamageReports.size() - shown) +
        " more damaged micro-models in this frame";
    }
    vtkWarningMacro(<< text);
  }
  this->LastUsedGpu = stats.UsedGpu;
  this->LastGpuModelsUploaded = stats.GpuModelsUploaded;
  this->LastGpuUploadTime = stats.GpuUploadSeconds;
  this->LastGpuKernelTime = stats.GpuKernelSeconds;
  this->LastGpuDownloadTime = stats.GpuDownloadSeconds;
  this->LastUsedBlendMode = frame.Request.Settings.blendMode;
  this->NumberOfRendererBuilds += stats.RendererBuilt ? 1 : 0;
  ++this->NumberOfFrames;

  // Unusable settings: one warning each time what is wrong changes, not every frame.
  const std::string settingWarning = JoinSentences(stats.SettingWarnings);
  if (!settingWarning.empty() && settingWarning != this->LastSettingWarning)
  {
    vtkWarningMacro(<< "Adaptive-FAM frame settings (lengths in the normalised [-1, 1] frame): "
                    << settingWarning);
  }
  this->LastSettingWarning = settingWarning;

  this->LastDeviceMessage = JoinSentences(stats.DeviceMessages);
  if (!this->LastDeviceMessage.empty() && !this->WarnedDevice)
  {
    this->WarnedDevice = true;
    if (this->RenderDevice == DEVICE_GPU)
    {
      vtkWarningMacro(<< "RenderDevice is GPU but " << this->LastDeviceMessage
                      << (stats.UsedGpu ? "" : "; rendering with the CPU ray caster"));
    }
    else
    {
      vtkLog(INFO,
        "Adaptive-FAM: " << this->LastDeviceMessage
                         << (stats.UsedGpu ? "" : "; rendering with the CPU ray caster"));
    }
  }
}

void vtkAFAMVolumeMapper::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << (this->FileName ? this->FileName : "(none)") << "\n";
  os << indent << "TimeStep: " << this->TimeStep << "\n";
  os << indent << "LodPolicy: " << this->LodPolicy << "\n";
  os << indent << "LodPixelBudget: " << this->LodPixelBudget << "\n";
  os << indent << "DrawMissingValues: " << (this->DrawMissingValues ? "On" : "Off") << "\n";
  os << indent << "CacheBudgetMB: " << this->CacheBudgetMB << "\n";
  os << indent << "Prefetcher: " << this->Prefetcher << "\n";
  os << indent << "RenderDevice: " << this->RenderDevice << "\n";
  os << indent << "DepthCompositing: " << this->DepthCompositing << "\n";
  os << indent << "SampleDistance: " << this->SampleDistance << "\n";
  os << indent << "UseJittering: " << this->UseJittering << "\n";
  os << indent << "NumberOfThreads: " << this->NumberOfThreads << "\n";
  os << indent << "Rank: " << this->Rank << " of " << this->NumberOfRanks << "\n";
  os << indent << "AutoAdjustImageScale: " << this->AutoAdjustImageScale << "\n";
  os << indent << "MinimumImageScale: " << this->MinimumImageScale << "\n";
  os << indent << "InteractiveMissBudget: " << this->InteractiveMissBudget << " ms\n";
  os << indent << "LastImageScale: " << this->LastImageScale << "\n";
  os << indent << "LastCachingTime: " << this->LastCachingTime << "\n";
  os << indent << "LastRenderTime: " << this->LastRenderTime << "\n";
  os << indent << "LastTotalTime: " << this->LastTotalTime << "\n";
  os << indent << "LastDepthReadTime: " << this->LastDepthReadTime << "\n";
  os << indent << "LastDrawTime: " << this->LastDrawTime << "\n";
  os << indent << "GpuImageInterop: " << this->GpuImageInterop << "\n";
  os << indent << "LastImageOnDevice: " << this->LastImageOnDevice << "\n";
  os << indent << "LastInteropProblem: " << this->LastInteropProblem << "\n";
  os << indent << "LastGpuUploadTime: " << this->LastGpuUploadTime << "\n";
  os << indent << "LastGpuKernelTime: " << this->LastGpuKernelTime << "\n";
  os << indent << "LastGpuDownloadTime: " << this->LastGpuDownloadTime << "\n";
  os << indent << "LastCacheHits: " << this->LastCacheHits << "\n";
  os << indent << "LastCacheMisses: " << this->LastCacheMisses << "\n";
  os << indent << "LastCulledBlocks: " << this->LastCulledBlocks << "\n";
  os << indent << "LastVisibleBlocks: " << this->LastVisibleBlocks << "\n";
  os << indent << "LastBytesRead: " << this->LastBytesRead << "\n";
  os << indent << "LastCacheBytes: " << this->LastCacheBytes << "\n";
  os << indent << "LastDamagedBlocks: " << this->LastDamagedBlocks << "\n";
  os << indent << "KnownDamagedBlocks: " << this->KnownDamagedBlocks << "\n";
  os << indent << "LastStandInBlocks: " << this->LastStandInBlocks << "\n";
  os << indent << "LastBlocksBehind: " << this->LastBlocksBehind << "\n";
  os << indent << "LastBytesBehind: " << this->LastBytesBehind << "\n";
  os << indent << "LastUsedGpu: " << this->LastUsedGpu << "\n";
  os << indent << "LastUsedBlendMode: " << this->LastUsedBlendMode << "\n";
  os << indent << "LastGpuModelsUploaded: " << this->LastGpuModelsUploaded << "\n";
  os << indent << "NumberOfRendererBuilds: " << this->NumberOfRendererBuilds << "\n";
  os << indent << "LastSettingWarning: " << this->LastSettingWarning << "\n";
  os << indent << "LastDepthLimitedPixels: " << this->LastDepthLimitedPixels << "\n";
  os << indent << "LastDeviceMessage: " << this->LastDeviceMessage << "\n";
  os << indent << "NumberOfFrames: " << this->NumberOfFrames << "\n";
}
