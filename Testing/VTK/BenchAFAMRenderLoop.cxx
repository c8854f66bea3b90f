// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// Frame times of vtkAFAMVolumeMapper inside a real VTK render loop, on the views `afam replay`
// renders, so that the two can be set side by side on the same file, views and image size.
//   BenchAFAMRenderLoop FILE.afam (--trajectory T.dat | --orbit N) [--size N] [--frames K]
//     [--device cpu|gpu] [--require-gpu] [--require-interop] [--host-draw] [--offscreen] [--cold]
//     [--plane] [--lod bands|screen] [--cache-mb MB] [--steps FIRST:LAST] [--view K]
//     [--csv OUT.csv]
// Each point of view becomes the VTK camera that casts the same rays as Core's Camera::fromPose
// (exact for cubic volumes); the transfer function is Core's preset over the file's value range,
// the LOD the paper's distance bands (--lod screen: screen-space LOD), sample distance 0.005 and
// opacity unit 0.01 in the normalised frame, shading on: `afam replay`'s defaults. A square window
// of --size pixels.
// --cold evicts the file from the OS page cache before every frame (`afam replay --cold`).
// Per frame: the whole window->Render() (with glFinish), the mapper's own time, its ray casting
// ("kernel": upload, cast and image readback on the GPU, as the host sees it), caching, the
// OpenGL round trips (depth read, the image's draw), and the GPU's own upload, kernel and
// download times (CUDA events; -1 on the CPU). "copies" = download + depth read + draw.
// Medians (and the 95th percentile of the whole call) last, in one line of name=value pairs.
// --require-gpu: exit status 1 unless every frame was cast on the GPU.
// --require-interop: exit status 1 unless every frame after the first went from the GPU to the
// window through CUDA-OpenGL interop. --host-draw: the mapper's GpuImageInterop off (the image
// comes back to the host and is uploaded). --offscreen: the window renders off screen (no swap to
// the X server). --plane: an opaque plane through the volume's centre (normal z), so that every
// frame reads the depth buffer for depth compositing.
// --steps FIRST:LAST plays a run: frame i draws step FIRST + i (back to FIRST after LAST; LAST <
// FIRST plays backwards) through the mapper's TimeStep, as ParaView's time does; with --view K
// the camera stands still (BenchRenderLoopScene.h).
#include "BenchRenderLoopScene.h"
#include "vtkAFAMReader.h"
#include "vtkAFAMVolumeMapper.h"

#include "afam/format/afam_file.hpp"
#include "afam/scene/camera.hpp"
#include "afam/scene/transfer_function.hpp"

#include "vtkActor.h"
#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkNew.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPlaneSource.h"
#include "vtkPolyDataMapper.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <fcntl.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace
{
struct Options : PathOptions
{
  bool Gpu = false, RequireGpu = false, RequireInterop = false, HostDraw = false, Offscreen = false;
  bool Plane = false, ScreenLod = false;
  double CacheMB = 512;
  long long FirstStep = -1, LastStep = -1; // --steps FIRST:LAST: a run's playback

  // The step frame i draws (-1: the file's only or first step, through the reader).
  long long StepOf(size_t i) const
  {
    if (FirstStep < 0)
    {
      return -1;
    }
    const long long span = std::llabs(LastStep - FirstStep) + 1;
    const long long k = static_cast<long long>(i % static_cast<size_t>(span));
    return LastStep >= FirstStep ? FirstStep + k : FirstStep - k;
  }
};

bool Parse(int argc, char* argv[], Options& o)
{
  for (int i = 1; i < argc; ++i)
  {
    const std::string a = argv[i];
    const bool hasValue = i + 1 < argc;
    if (ParsePathOption(argc, argv, i, o))
      continue;
    if (a == "--device" && hasValue)
      o.Gpu = std::string(argv[++i]) == "gpu";
    else if (a == "--lod" && hasValue)
      o.ScreenLod = std::string(argv[++i]) == "screen";
    else if (a == "--cache-mb" && hasValue)
      o.CacheMB = std::atof(argv[++i]);
    else if (a == "--require-gpu")
      o.RequireGpu = true;
    else if (a == "--require-interop")
      o.RequireInterop = true;
    else if (a == "--host-draw")
      o.HostDraw = true;
    else if (a == "--offscreen")
      o.Offscreen = true;
    else if (a == "--plane")
      o.Plane = true;
    else if (a == "--steps" && hasValue &&
      std::sscanf(argv[++i], "%lld:%lld", &o.FirstStep, &o.LastStep) == 2 && o.FirstStep >= 0 &&
      o.LastStep >= 0)
      continue;
    else
    {
      std::cerr << "BenchAFAMRenderLoop: unknown or incomplete argument '" << a << "'\n";
      return false;
    }
  }
  if (!PathOptionsComplete(o) || !o.MoreFiles.empty())
  {
    std::cerr << "usage: BenchAFAMRenderLoop FILE.afam (--trajectory T.dat | --orbit N) [--size N "
                 "(16..8192)] [--frames K] [--device cpu|gpu] [--require-gpu] [--require-interop] "
                 "[--host-draw] [--offscreen] [--cold] [--plane] [--lod bands|screen] "
                 "[--cache-mb MB] [--steps FIRST:LAST] [--view K] [--csv OUT.csv]\n";
    return false;
  }
  return true;
}

// Seconds to milliseconds, keeping -1 (not cast on the GPU) as -1.
double Milliseconds(double seconds)
{
  return seconds < 0 ? -1.0 : 1e3 * seconds;
}

struct FrameTimes
{
  double RenderCall, Mapper, Kernel, Caching, DepthRead, Draw;
  double GpuUpload, GpuKernel, GpuDownload; // CUDA events; -1 on the CPU
  bool Gpu, Interop;
  long long Visible, Misses;
};
}

int main(int argc, char* argv[])
{
  Options o;
  if (!Parse(argc, argv, o))
  {
    return 2;
  }
  std::vector<afam::Pose> poses;
  std::shared_ptr<const afam::AfamFile> file;
  try
  {
    poses = LoadPoses(o);
    file = afam::AfamFile::open(o.File);
  }
  catch (const std::exception& e)
  {
    std::cerr << "BenchAFAMRenderLoop: " << e.what() << "\n";
    return 2;
  }

  if (o.FirstStep >= 0 && (o.FirstStep >= file->stepCount() || o.LastStep >= file->stepCount()))
  {
    std::cerr << "BenchAFAMRenderLoop: --steps outside the " << file->stepCount() << " steps of "
              << o.File << "\n";
    return 2;
  }
  vtkNew<vtkAFAMReader> reader;
  reader->SetFileName(o.File.c_str());
  vtkNew<vtkAFAMVolumeMapper> mapper;
  if (o.FirstStep >= 0)
  {
    mapper->SetFileName(o.File.c_str()); // the step set per frame (TimeStep)
  }
  else
  {
    mapper->SetInputConnection(reader->GetOutputPort());
  }
  if (o.ScreenLod)
  {
    mapper->SetLodPolicyToScreenSpace();
  }
  else
  {
    mapper->SetLodPolicyToDistanceBands();
  }
  mapper->SetCacheBudgetMB(o.CacheMB);
  mapper->SetRenderDevice(
    o.Gpu ? vtkAFAMVolumeMapper::DEVICE_GPU : vtkAFAMVolumeMapper::DEVICE_CPU);
  mapper->SetGpuImageInterop(!o.HostDraw);
  const double* b = mapper->GetBounds();
  const VolumeBox box = BoxOf(b);
  const double* c = box.Centre;
  const double* h = box.Half;
  const double unit = box.Unit;
  if (!(unit > 0))
  {
    std::cerr << "BenchAFAMRenderLoop: " << o.File << " has an empty volume box\n";
    return 2;
  }
  mapper->SetSampleDistance(0.005 * unit);
  vtkNew<vtkVolume> volume;
  volume->SetMapper(mapper);
  SetPresetTransferFunction(
    volume->GetProperty(), file->header().valueMin, file->header().valueMax, unit);
  vtkNew<vtkRenderer> renderer;
  renderer->AddVolume(volume);
  if (o.Plane)
  {
    vtkNew<vtkPlaneSource> plane;
    plane->SetOrigin(b[0], b[2], c[2]);
    plane->SetPoint1(b[1], b[2], c[2]);
    plane->SetPoint2(b[0], b[3], c[2]);
    vtkNew<vtkPolyDataMapper> planeMapper;
    planeMapper->SetInputConnection(plane->GetOutputPort());
    vtkNew<vtkActor> planeActor;
    planeActor->SetMapper(planeMapper);
    renderer->AddActor(planeActor); // the renderer keeps the actor, the actor its mapper
  }
  vtkNew<vtkRenderWindow> window;
  window->SetSize(o.Size, o.Size);
  window->SetMultiSamples(0);
  window->SetOffScreenRendering(o.Offscreen ? 1 : 0);
  window->AddRenderer(renderer);

  std::ofstream csv;
  if (!o.Csv.empty())
  {
    csv.open(o.Csv);
    csv << "pov,render_call_ms,mapper_ms,kernel_ms,caching_ms,depth_read_ms,draw_ms,"
           "gpu_upload_ms,gpu_kernel_ms,gpu_download_ms,gpu,interop,visible,misses\n";
  }
  std::vector<FrameTimes> frames;
  for (size_t i = 0; i < poses.size(); ++i)
  {
    PlaceCamera(renderer->GetActiveCamera(), poses[i], c, h, o.Size);
    renderer->ResetCameraClippingRange();
    if (o.FirstStep >= 0)
    {
      mapper->SetTimeStep(static_cast<vtkTypeInt64>(o.StepOf(i)));
    }
    if (o.Cold)
    {
      (void)::posix_fadvise(file->nativeHandle(), 0, 0, POSIX_FADV_DONTNEED);
    }
    const auto t0 = std::chrono::steady_clock::now();
    window->Render();
    window->WaitForCompletion();
    const double call =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    frames.push_back({ call,
      1e3 * mapper->GetLastTotalTime(),
      1e3 * mapper->GetLastRenderTime(),
      1e3 * mapper->GetLastCachingTime(),
      1e3 * mapper->GetLastDepthReadTime(),
      1e3 * mapper->GetLastDrawTime(),
      Milliseconds(mapper->GetLastGpuUploadTime()),
      Milliseconds(mapper->GetLastGpuKernelTime()),
      Milliseconds(mapper->GetLastGpuDownloadTime()),
      mapper->GetLastUsedGpu(),
      mapper->GetLastImageOnDevice(),
      static_cast<long long>(mapper->GetLastVisibleBlocks()),
      static_cast<long long>(mapper->GetLastCacheMisses()) });
    const FrameTimes& f = frames.back();
    if (csv.is_open())
    {
      csv << i << ',' << f.RenderCall << ',' << f.Mapper << ',' << f.Kernel << ',' << f.Caching
          << ',' << f.DepthRead << ',' << f.Draw << ',' << f.GpuUpload << ',' << f.GpuKernel << ','
          << f.GpuDownload << ',' << f.Gpu << ',' << f.Interop << ',' << f.Visible << ','
          << f.Misses << '\n';
    }
  }
  // Which OpenGL the window got (Mesa's llvmpipe or the GPU's own driver).
  std::istringstream capabilities(window->ReportCapabilities() ? window->ReportCapabilities() : "");
  for (std::string line; std::getline(capabilities, line);)
  {
    if (line.find("renderer string") != std::string::npos ||
      line.find("version string") != std::string::npos)
    {
      std::cout << "gl: " << line << "\n";
    }
  }
  if (frames.empty() || mapper->GetNumberOfFrames() < static_cast<vtkTypeInt64>(frames.size()))
  {
    std::cerr << "BenchAFAMRenderLoop: the mapper drew " << mapper->GetNumberOfFrames() << " of "
              << frames.size() << " frames\n";
    return 1;
  }

  // Medians over every frame but the first (context, pool and cache set-up), which is reported
  // on its own.
  std::map<std::string, std::vector<double>> series;
  size_t onGpu = 0, interop = 0;
  for (size_t i = 0; i < frames.size(); ++i)
  {
    const FrameTimes& f = frames[i];
    onGpu += f.Gpu ? 1 : 0;
    interop += f.Interop ? 1 : 0;
    if (i == 0 && frames.size() > 1)
    {
      continue;
    }
    series["render_call"].push_back(f.RenderCall);
    series["mapper"].push_back(f.Mapper);
    series["kernel"].push_back(f.Kernel);
    series["caching"].push_back(f.Caching);
    // The image's and depth's trips: copy back from the GPU (0 with interop), draw, depth read.
    series["copies"].push_back(std::max(0.0, f.GpuDownload) + f.DepthRead + f.Draw);
    series["gpu_upload"].push_back(f.GpuUpload);
    series["gpu_kernel"].push_back(f.GpuKernel);
    series["gpu_download"].push_back(f.GpuDownload);
    series["depth_read"].push_back(f.DepthRead);
    series["draw"].push_back(f.Draw);
  }
  const double renderCall = Median(series["render_call"]);
  std::printf("vtk_render_loop file=%s steps=%lld:%lld povs=%zu size=%dx%d device=%s cold=%d "
              "offscreen=%d plane=%d gpu_frames=%zu interop_frames=%zu first_frame_ms=%.3f "
              "message='%s' interop='%s'\n",
    o.File.c_str(),
    o.FirstStep,
    o.LastStep,
    frames.size(),
    o.Size,
    o.Size,
    o.Gpu ? "gpu" : "cpu",
    o.Cold ? 1 : 0,
    o.Offscreen ? 1 : 0,
    o.Plane ? 1 : 0,
    onGpu,
    interop,
    frames[0].RenderCall,
    mapper->GetLastDeviceMessage(),
    mapper->GetLastInteropProblem());
  std::printf("median_render_call_ms=%.3f median_mapper_ms=%.3f median_kernel_ms=%.3f "
              "median_caching_ms=%.3f median_copies_ms=%.3f median_depth_read_ms=%.3f "
              "median_draw_ms=%.3f median_gpu_upload_ms=%.3f median_gpu_kernel_ms=%.3f "
              "median_gpu_download_ms=%.3f fps=%.1f p95_render_call_ms=%.3f\n",
    renderCall,
    Median(series["mapper"]),
    Median(series["kernel"]),
    Median(series["caching"]),
    Median(series["copies"]),
    Median(series["depth_read"]),
    Median(series["draw"]),
    Median(series["gpu_upload"]),
    Median(series["gpu_kernel"]),
    Median(series["gpu_download"]),
    renderCall > 0 ? 1e3 / renderCall : 0.0,
    Quantile(series["render_call"], 0.95));
  if (o.RequireGpu && onGpu != frames.size())
  {
    std::cerr << "BenchAFAMRenderLoop: --require-gpu and only " << onGpu << " of " << frames.size()
              << " frames were cast on the GPU: " << mapper->GetLastDeviceMessage() << "\n";
    return 1;
  }
  // The first frame builds the renderer (and draws through the host); every later one must not.
  if (o.RequireInterop && (frames.size() < 2 || interop + 1 < frames.size()))
  {
    std::cerr << "BenchAFAMRenderLoop: --require-interop and only " << interop << " of "
              << frames.size()
              << " frames went through CUDA-OpenGL interop: " << mapper->GetLastInteropProblem()
              << "\n";
    return 1;
  }
  return 0;
}
