// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMVolumeMapper.h"

#include "vtkAFAMCoreRenderer.h"
#include "vtkAFAMModelTree.h"

#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkInformation.h"
#include "vtkLogger.h"
#include "vtkMath.h"
#include "vtkMatrix4x4.h"
#include "vtkMultiBlockDataSet.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkOpenGLRenderWindow.h"
#include "vtkOpenGLState.h"
#include "vtkPiecewiseFunction.h"
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
{
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
  if (this->FileName && *this->FileName)
  {
    return this->FileName;
  }
  if (this->GetNumberOfInputConnections(0) > 0)
  {
    this->UpdateInformation();
    this->GetInputAlgorithm()->Update();
    return vtkAFAMModelTree::FileName(vtkMultiBlockDataSet::SafeDownCast(this->GetInputDataObject(0, 0)));
  }
  return {};
}

bool vtkAFAMVolumeMapper::EnsureOpen()
{
  const std::string path = this->ResolveFileName();
  if (path.empty())
  {
    vtkErrorMacro(<< "No .afam file: set FileName or connect the output of vtkAFAMReader/vtkAFAMEncoder.");
    return false;
  }
  try
  {
    this->Core->Open(path);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return false;
  }
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

bool vtkAFAMVolumeMapper::HasCudaRenderer()
{
  return vtkAFAMCoreRenderer::HasCuda();
}

bool vtkAFAMVolumeMapper::ReadDepthLimits(vtkRenderer* ren, const double toFrame[12],
  const afam::Camera& camera, int width, int height, std::vector<float>& limits)
{
  int w = 0, h = 0, x0 = 0, y0 = 0;
  ren->GetTiledSizeAndOrigin(&w, &h, &x0, &y0);
  if (w != width || h != height)
  {
    return false;
  }
  std::vector<float> depth(static_cast<size_t>(width) * static_cast<size_t>(height));
  if (ren->GetRenderWindow()->GetZbufferData(x0, y0, x0 + w - 1, y0 + h - 1, depth.data()) !=
    VTK_OK)
  {
    vtkWarningMacro(<< "cannot read the z-buffer; the volume is blended over opaque geometry");
    return false;
  }
  // Window depth -> world point: inverse of the camera's composite projection (NDC z in [-1, 1]),
  // which linearises the perspective depth exactly; -> normalised frame -> ray parameter t:
  // perspective, the distance from the eye; parallel, (p - eye).n / (d.n) with n the image
  // plane's normal and d the unit view direction (every ray starts on the eye plane).
  vtkNew<vtkMatrix4x4> inverse;
  vtkMatrix4x4::Invert(ren->GetActiveCamera()->GetCompositeProjectionTransformMatrix(
                         ren->GetTiledAspectRatio(), -1, 1),
    inverse);
  const double* m = inverse->GetData();
  const int cw = camera.width, ch = camera.height; // the cast image, at most the tile's size
  const afam::Vec3& e = camera.eye;
  const afam::Vec3 n = afam::cross(camera.right, camera.up); // the image plane's normal
  const double dn = afam::dot(camera.forward, n) / std::sqrt(afam::dot(camera.forward, camera.forward));
  limits.assign(static_cast<size_t>(cw) * static_cast<size_t>(ch),
    std::numeric_limits<float>::infinity());
  bool any = false;
  for (int y = 0; y < ch; ++y) // y = 0: bottom row (OpenGL)
  {
    const double ny = 2.0 * (y + 0.5) / ch - 1.0;
    float* row = &limits[static_cast<size_t>(ch - 1 - y) * cw]; // Core: row 0 = top
    const int y0t = y * height / ch, y1t = std::max(y0t + 1, (y + 1) * height / ch);
    for (int x = 0; x < cw; ++x)
    {
      // The nearest opaque surface among the tile pixels this pixel covers.
      const int x0t = x * width / cw, x1t = std::max(x0t + 1, (x + 1) * width / cw);
      float z = 1.0f;
      for (int yt = y0t; yt < y1t; ++yt)
      {
        for (int xt = x0t; xt < x1t; ++xt)
        {
          z = std::min(z, depth[static_cast<size_t>(yt) * width + xt]);
        }
      }
      if (!(z < 1.0f))
      {
        continue; // the far plane: nothing opaque here
      }
      const double ndc[4] = { 2.0 * (x + 0.5) / cw - 1.0, ny, 2.0 * z - 1.0, 1.0 };
      double p[4];
      for (int r = 0; r < 4; ++r)
      {
        p[r] = m[4 * r] * ndc[0] + m[4 * r + 1] * ndc[1] + m[4 * r + 2] * ndc[2] + m[4 * r + 3];
      }
      if (!(std::abs(p[3]) > 0))
      {
        continue;
      }
      const double w[3] = { p[0] / p[3], p[1] / p[3], p[2] / p[3] };
      double q[3]; // normalised frame, relative to the eye
      for (int a = 0; a < 3; ++a)
      {
        q[a] = toFrame[4 * a] * w[0] + toFrame[4 * a + 1] * w[1] + toFrame[4 * a + 2] * w[2] +
          toFrame[4 * a + 3] - e[a];
      }
      row[x] = static_cast<float>(camera.parallel
          ? (q[0] * n[0] + q[1] * n[1] + q[2] * n[2]) / dn
          : std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]));
      any = true;
    }
  }
  return any;
}

double* vtkAFAMVolumeMapper::GetBounds()
{
  vtkMath::UninitializeBounds(this->Bounds);
  if (this->Core->Path().empty())
  {
    const std::string path = this->ResolveFileName();
    if (path.empty())
    {
      return this->Bounds;
    }
    try
    {
      this->Core->Open(path);
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

void vtkAFAMVolumeMapper::Render(vtkRenderer* ren, vtkVolume* vol)
{
  const auto start = std::chrono::steady_clock::now();
  if (!this->EnsureOpen())
  {
    return;
  }
  auto* renWin = vtkOpenGLRenderWindow::SafeDownCast(ren->GetRenderWindow());
  vtkCamera* cam = ren->GetActiveCamera();
  vtkVolumeProperty* property = vol->GetProperty();
  if (!renWin || !cam || !property)
  {
    vtkErrorMacro(<< "needs an OpenGL render window, an active camera and a volume property");
    return;
  }
  if (cam->GetUseOffAxisProjection())
  {
    vtkErrorMacro(<< "off-axis (head-tracked) projection is not supported by the Adaptive-FAM "
                     "renderer; nothing is drawn");
    return;
  }
  // The image is the renderer's part of the current tile: with a magnified screenshot VTK renders
  // tiles of the window's size, narrowing the view angle (or parallel scale) and moving the
  // camera's WindowCenter per tile.
  int width = 0, height = 0, tileX = 0, tileY = 0;
  ren->GetTiledSizeAndOrigin(&width, &height, &tileX, &tileY);
  if (width < 1 || height < 1)
  {
    return;
  }
  // Interactive frames: a smaller image that fits the allotted time (see AutoAdjustImageScale).
  double scale = 1.0;
  const double rate = renWin->GetDesiredUpdateRate();
  if (this->AutoAdjustImageScale && rate > 1.0 && this->SecondsPerPixel > 0)
  {
    const double allotted = vol->GetAllocatedRenderTime();
    const double budget = allotted > 0 ? std::min(allotted, 1.0 / rate) : 1.0 / rate;
    scale = std::sqrt(budget / (this->SecondsPerPixel * width * height));
    scale = std::max(this->MinimumImageScale, std::min(1.0, scale));
  }
  const int castWidth = std::max(1, static_cast<int>(std::lround(width * scale)));
  const int castHeight = std::max(1, static_cast<int>(std::lround(height * scale)));

  // World -> normalised frame: the inverse of the vtkVolume's matrix takes the world to the data,
  // then the data box maps to [-1, 1]^3, each axis on its own (paper).
  double* b = this->GetBounds();
  double center[3], half[3];
  for (int a = 0; a < 3; ++a)
  {
    center[a] = 0.5 * (b[2 * a] + b[2 * a + 1]);
    half[a] = 0.5 * (b[2 * a + 1] - b[2 * a]);
    if (!(half[a] > 0))
    {
      half[a] = 1;
    }
  }
  vtkMatrix4x4* toWorld = vol->GetMatrix();
  const double det = toWorld->Determinant();
  if (!(std::abs(det) > 1e-300) || !std::isfinite(det))
  {
    vtkErrorMacro(<< "the volume's transform is singular (a zero Scale?) or not finite; "
                     "nothing is drawn");
    return;
  }
  vtkNew<vtkMatrix4x4> toData;
  vtkMatrix4x4::Invert(toWorld, toData);
  double toFrame[12];
  std::array<double, 9> linear;
  afam::Vec3 offset;
  for (int r = 0; r < 3; ++r)
  {
    for (int c = 0; c < 4; ++c)
    {
      toFrame[4 * r + c] = (toData->GetElement(r, c) - (c == 3 ? center[r] : 0.0)) / half[r];
    }
    for (int c = 0; c < 3; ++c)
    {
      linear[static_cast<size_t>(3 * r + c)] = toFrame[4 * r + c];
    }
    offset[static_cast<size_t>(r)] = toFrame[4 * r + 3];
  }
  double pos[3], focal[3], up[3], clip[2];
  cam->GetPosition(pos);
  cam->GetFocalPoint(focal);
  cam->GetViewUp(up);
  cam->GetClippingRange(clip);

  vtkAFAMFrameRequest request;
  try
  {
    const afam::Vec3 eyeW{ pos[0], pos[1], pos[2] }, focalW{ focal[0], focal[1], focal[2] },
      upW{ up[0], up[1], up[2] };
    afam::Camera world = cam->GetParallelProjection()
      ? afam::Camera::parallelLookAt(eyeW, focalW, upW, cam->GetParallelScale(), castWidth, castHeight)
      : afam::Camera::lookAt(eyeW, focalW, upW, cam->GetViewAngle(), castWidth, castHeight);
    // VTK's frustum: half extents from the tiled aspect ratio, the angle (or scale) vertical
    // unless UseHorizontalViewAngle, shifted by WindowCenter in units of the half extents.
    const double aspect = ren->GetTiledAspectRatio();
    if (cam->GetUseHorizontalViewAngle() && !cam->GetParallelProjection())
    {
      world.tanHalfX = std::tan(0.5 * vtkMath::RadiansFromDegrees(cam->GetViewAngle()));
      world.tanHalfY = world.tanHalfX / aspect;
    }
    else
    {
      world.tanHalfX = world.tanHalfY * aspect;
    }
    const double* center = cam->GetWindowCenter();
    world.centerX = center[0] * world.tanHalfX;
    world.centerY = center[1] * world.tanHalfY;
    world.nearDistance = std::max(0.0, clip[0]);
    request.Camera = world.mapped(linear, offset);
    request.Camera.nearDistance = std::max(1e-4, request.Camera.nearDistance);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return;
  }
  // World lengths -> normalised-frame lengths (Camera::mapped's lengthUnit; the step metric keeps
  // steps and opacities right in every direction when the map stretches axes differently).
  const double lengthUnit = request.Camera.lengthUnit;

  // Transfer functions and shading from the volume property (component 0).
  if (vtkColorTransferFunction* ctf = property->GetRGBTransferFunction(0))
  {
    double node[6];
    for (int i = 0; i < ctf->GetSize(); ++i)
    {
      ctf->GetNodeValue(i, node);
      request.Transfer.colors.push_back({ node[0], node[1], node[2], node[3] });
    }
  }
  if (vtkPiecewiseFunction* pwf = property->GetScalarOpacity(0))
  {
    double node[4];
    for (int i = 0; i < pwf->GetSize(); ++i)
    {
      pwf->GetNodeValue(i, node);
      request.Transfer.opacities.push_back({ node[0], node[1] });
    }
  }
  const double unitDistance = property->GetScalarOpacityUnitDistance(0);
  request.Transfer.referenceDistance = std::max(1e-6, unitDistance / lengthUnit);
  request.Shading = property->GetShade(0) != 0;
  const double sampleWorld = this->SampleDistance > 0 ? this->SampleDistance : 0.5 * unitDistance;
  request.SampleDistance = sampleWorld / lengthUnit;
  request.LodPolicy = this->LodPolicy;
  request.CacheBudgetMB = this->CacheBudgetMB;
  request.Prefetcher = this->Prefetcher;
  request.Device = this->RenderDevice;
  request.Threads = this->NumberOfThreads;
  // Composite, maximum, minimum and average intensity (VTK's numbering); other modes are drawn
  // composite, with one warning.
  const int blend = this->GetBlendMode();
  request.BlendMode = blend >= 0 && blend <= 3 ? blend : 0;
  if (request.BlendMode != blend && !this->WarnedBlendMode)
  {
    this->WarnedBlendMode = true;
    vtkWarningMacro(<< "blend mode " << blend
                    << " is not supported by the Adaptive-FAM renderer (composite, maximum, "
                       "minimum and average intensity are); drawing it composite");
  }

  // Opaque geometry drawn so far stops the rays (see the class documentation).
  std::vector<float> limits;
  this->LastDepthLimitedPixels = 0;
  if (this->DepthCompositing)
  {
    if (this->ReadDepthLimits(ren, toFrame, request.Camera, width, height, limits))
    {
      request.MaxDistance = limits.data();
      this->LastDepthLimitedPixels = static_cast<vtkTypeInt64>(std::count_if(limits.begin(),
        limits.end(), [](float t) { return t < std::numeric_limits<float>::infinity(); }));
    }
  }

  afam::ImageRGBA image;
  vtkAFAMFrameStats stats;
  try
  {
    this->Core->Render(request, image, stats);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return;
  }
  if (image.width != castWidth || image.height != castHeight)
  {
    vtkErrorMacro(<< "Core returned a " << image.width << "x" << image.height << " image for a "
                  << castWidth << "x" << castHeight << " request");
    return;
  }

  // Core's row 0 is the top; OpenGL's is the bottom.
  std::vector<float> flipped(image.rgba.size());
  const size_t row = static_cast<size_t>(castWidth) * 4;
  for (int y = 0; y < castHeight; ++y)
  {
    std::copy_n(
      &image.rgba[static_cast<size_t>(castHeight - 1 - y) * row], row, &flipped[y * row]);
  }

  // Blend the premultiplied image over the viewport's content.
  vtkOpenGLState* state = renWin->GetState();
  vtkOpenGLState::ScopedglEnableDisable blendSaver(state, GL_BLEND);
  vtkOpenGLState::ScopedglEnableDisable depthSaver(state, GL_DEPTH_TEST);
  vtkOpenGLState::ScopedglBlendFuncSeparate blendFuncSaver(state);
  vtkOpenGLState::ScopedglDepthMask depthMaskSaver(state);
  state->vtkglEnable(GL_BLEND);
  state->vtkglBlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  state->vtkglDisable(GL_DEPTH_TEST);
  state->vtkglDepthMask(GL_FALSE);
  renWin->DrawPixels(castWidth, castHeight, 4, VTK_FLOAT, flipped.data()); // scaled to the viewport

  // Time per cast pixel, for the next interactive frame's scale: the latest still frame sets it,
  // interactive frames blend in (they are smaller, so fixed costs weigh more there).
  const double frameSeconds = stats.RenderSeconds + stats.CachingSeconds;
  const double perPixel = frameSeconds / (static_cast<double>(castWidth) * castHeight);
  this->SecondsPerPixel = (this->SecondsPerPixel > 0 && scale < 1.0)
    ? 0.5 * (this->SecondsPerPixel + perPixel)
    : perPixel;
  this->LastImageScale = static_cast<double>(castWidth) / width;

  this->LastCachingTime = stats.CachingSeconds;
  this->LastRenderTime = stats.RenderSeconds;
  this->LastCacheHits = stats.CacheHits;
  this->LastCacheMisses = stats.CacheMisses;
  this->LastCulledBlocks = stats.CulledBlocks;
  this->LastVisibleBlocks = stats.VisibleBlocks;
  this->LastBytesRead = static_cast<vtkTypeInt64>(stats.BytesRead);
  this->LastUsedGpu = stats.UsedGpu;
  this->LastDeviceMessage.clear();
  for (const std::string& m : stats.DeviceMessages)
  {
    this->LastDeviceMessage += (this->LastDeviceMessage.empty() ? "" : "; ") + m;
  }
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
      vtkLog(INFO, "Adaptive-FAM: " << this->LastDeviceMessage
                                    << (stats.UsedGpu ? "" : "; rendering with the CPU ray caster"));
    }
  }
  ++this->NumberOfFrames;
  this->LastTotalTime =
    std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void vtkAFAMVolumeMapper::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << (this->FileName ? this->FileName : "(none)") << "\n";
  os << indent << "LodPolicy: " << this->LodPolicy << "\n";
  os << indent << "CacheBudgetMB: " << this->CacheBudgetMB << "\n";
  os << indent << "Prefetcher: " << this->Prefetcher << "\n";
  os << indent << "RenderDevice: " << this->RenderDevice << "\n";
  os << indent << "DepthCompositing: " << this->DepthCompositing << "\n";
  os << indent << "SampleDistance: " << this->SampleDistance << "\n";
  os << indent << "NumberOfThreads: " << this->NumberOfThreads << "\n";
  os << indent << "AutoAdjustImageScale: " << this->AutoAdjustImageScale << "\n";
  os << indent << "MinimumImageScale: " << this->MinimumImageScale << "\n";
  os << indent << "LastImageScale: " << this->LastImageScale << "\n";
  os << indent << "LastCachingTime: " << this->LastCachingTime << "\n";
  os << indent << "LastRenderTime: " << this->LastRenderTime << "\n";
  os << indent << "LastTotalTime: " << this->LastTotalTime << "\n";
  os << indent << "LastCacheHits: " << this->LastCacheHits << "\n";
  os << indent << "LastCacheMisses: " << this->LastCacheMisses << "\n";
  os << indent << "LastCulledBlocks: " << this->LastCulledBlocks << "\n";
  os << indent << "LastVisibleBlocks: " << this->LastVisibleBlocks << "\n";
  os << indent << "LastBytesRead: " << this->LastBytesRead << "\n";
  os << indent << "LastUsedGpu: " << this->LastUsedGpu << "\n";
  os << indent << "LastDepthLimitedPixels: " << this->LastDepthLimitedPixels << "\n";
  os << indent << "LastDeviceMessage: " << this->LastDeviceMessage << "\n";
  os << indent << "NumberOfFrames: " << this->NumberOfFrames << "\n";
}
