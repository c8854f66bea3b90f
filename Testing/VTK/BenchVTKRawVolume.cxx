// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// What a user would run instead of the plugin: VTK's own GPU ray caster (vtkGPUVolumeRayCastMapper)
// on the raw samples, on the views, image size and transfer function of BenchAFAMRenderLoop and
// `afam replay`, so that the three can be set side by side.
//   BenchVTKRawVolume IN_XxYxZ_type.raw [STEP1.raw ...] (--trajectory T.dat | --orbit N)
//     [--size N] [--frames K] [--view K] [--cold] [--csv OUT.csv]
// The volume is read into a vtkImageData of its own sample type (no conversion), its value range
// scanned (the .afam header's range, which the transfer function spans), and drawn with
// trilinear interpolation, shading on, sample distance 0.005 and opacity unit 0.01 in the
// normalised frame. --cold evicts the raw file from the OS page cache before it is read.
// Prints the time to the first image (read + range + first Render(), which uploads the volume
// to the GPU), then the medians and 95th percentile of the later frames' Render() (glFinish'ed).
// Several inputs are a run's steps (one grid): frame i draws input i (back to the first after the
// last), read from the page cache into a new image and given to the mapper, which uploads it: what
// playing a file series in VTK costs; each frame's time includes that read.
#include "BenchRenderLoopScene.h"

#include "afam/base/errors.hpp"
#include "afam/volume/sample_type.hpp"
#include "afam/volume/volume_source.hpp"

#include "vtkDataArray.h"
#include "vtkGPUVolumeRayCastMapper.h"
#include "vtkImageData.h"
#include "vtkPointData.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkType.h"
#include "vtkVolume.h"

#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace
{
using Options = PathOptions;

bool Parse(int argc, char* argv[], Options& o)
{
  for (int i = 1; i < argc; ++i)
  {
    if (!ParsePathOption(argc, argv, i, o))
    {
      std::cerr << "BenchVTKRawVolume: unknown or incomplete argument '" << argv[i] << "'\n";
      return false;
    }
  }
  if (!PathOptionsComplete(o))
  {
    std::cerr << "usage: BenchVTKRawVolume IN_XxYxZ_type.raw [STEP1.raw ...] (--trajectory T.dat "
                 "| --orbit N) [--size N (16..8192)] [--frames K] [--view K] [--cold] "
                 "[--csv OUT.csv]\n";
    return false;
  }
  return true;
}

// The VTK scalar type that holds `type` as it is.
int VtkType(afam::SampleType type)
{
  switch (type)
  {
    case afam::SampleType::Int8:
      return VTK_SIGNED_CHAR;
    case afam::SampleType::UInt8:
      return VTK_UNSIGNED_CHAR;
    case afam::SampleType::Int16:
      return VTK_SHORT;
    case afam::SampleType::UInt16:
      return VTK_UNSIGNED_SHORT;
    case afam::SampleType::Int32:
      return VTK_INT;
    case afam::SampleType::UInt32:
      return VTK_UNSIGNED_INT;
    case afam::SampleType::Int64:
      return VTK_LONG_LONG;
    case afam::SampleType::UInt64:
      return VTK_UNSIGNED_LONG_LONG;
    case afam::SampleType::Float32:
      return VTK_FLOAT;
    case afam::SampleType::Float64:
      return VTK_DOUBLE;
  }
  return VTK_DOUBLE;
}

// The raw file's samples, as they are on disk, in a new image (origin 0, spacing 1: what
// `afam encode` gives the same file).
vtkSmartPointer<vtkImageData> ReadRaw(const std::string& path, bool cold)
{
  afam::Index3 dims;
  afam::SampleType type;
  if (!afam::parseRawName(path, dims, type))
  {
    throw afam::InvalidArgument(path + ": not named name_XxYxZ_type.raw");
  }
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(
    static_cast<int>(dims[0]), static_cast<int>(dims[1]), static_cast<int>(dims[2]));
  image->AllocateScalars(VtkType(type), 1);
  const size_t bytes = static_cast<size_t>(dims[0] * dims[1] * dims[2]) *
    static_cast<size_t>(afam::sampleTypeSize(type));
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0)
  {
    throw afam::IoError(path + ": cannot open");
  }
  if (cold)
  {
    (void)::posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);
  }
  auto* out = static_cast<char*>(image->GetScalarPointer());
  size_t done = 0;
  while (done < bytes)
  {
    const ssize_t got = ::pread(fd, out + done, bytes - done, static_cast<off_t>(done));
    if (got <= 0)
    {
      ::close(fd);
      throw afam::IoError(path + ": short read (is the file " + std::to_string(bytes) + " bytes?)");
    }
    done += static_cast<size_t>(got);
  }
  ::close(fd);
  return image;
}
}

int main(int argc, char* argv[])
{
  Options o;
  if (!Parse(argc, argv, o))
  {
    return 2;
  }
  std::vector<afam::Pose> poses;
  vtkSmartPointer<vtkImageData> image;
  const auto start = std::chrono::steady_clock::now();
  double range[2];
  try
  {
    poses = LoadPoses(o);
    image = ReadRaw(o.File, o.Cold);
    image->GetPointData()->GetScalars()->GetRange(range);
  }
  catch (const std::exception& e)
  {
    std::cerr << "BenchVTKRawVolume: " << e.what() << "\n";
    return 2;
  }
  const double loadMs =
    std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  const double* b = image->GetBounds();
  const VolumeBox box = BoxOf(b);
  const double* c = box.Centre;
  const double* h = box.Half;
  const double unit = box.Unit;
  if (!(unit > 0))
  {
    std::cerr << "BenchVTKRawVolume: " << o.File << " has an empty volume box\n";
    return 2;
  }
  vtkNew<vtkGPUVolumeRayCastMapper> mapper;
  mapper->SetInputData(image);
  mapper->AutoAdjustSampleDistancesOff();
  mapper->SetSampleDistance(0.005 * unit);
  mapper->SetMaxMemoryFraction(1.0);
  vtkNew<vtkVolume> volume;
  volume->SetMapper(mapper);
  SetPresetTransferFunction(volume->GetProperty(), range[0], range[1], unit);
  volume->GetProperty()->SetInterpolationTypeToLinear();
  vtkNew<vtkRenderer> renderer;
  renderer->AddVolume(volume);
  vtkNew<vtkRenderWindow> window;
  window->SetSize(o.Size, o.Size);
  window->SetMultiSamples(0);
  window->AddRenderer(renderer);

  std::ofstream csv;
  if (!o.Csv.empty())
  {
    csv.open(o.Csv);
    csv << "pov,render_call_ms\n";
  }
  std::vector<double> calls;
  for (size_t i = 0; i < poses.size(); ++i)
  {
    PlaceCamera(renderer->GetActiveCamera(), poses[i], c, h, o.Size);
    renderer->ResetCameraClippingRange();
    const auto t0 = std::chrono::steady_clock::now();
    const size_t steps = 1 + o.MoreFiles.size();
    if (steps > 1 && i > 0)
    {
      const size_t k = i % steps;
      try
      {
        mapper->SetInputData(ReadRaw(k == 0 ? o.File : o.MoreFiles[k - 1], false));
      }
      catch (const std::exception& e)
      {
        std::cerr << "BenchVTKRawVolume: " << e.what() << "\n";
        return 2;
      }
    }
    window->Render();
    window->WaitForCompletion();
    calls.push_back(
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    if (csv.is_open())
    {
      csv << i << ',' << calls.back() << '\n';
    }
  }
  std::istringstream capabilities(window->ReportCapabilities() ? window->ReportCapabilities() : "");
  for (std::string line; std::getline(capabilities, line);)
  {
    if (line.find("renderer string") != std::string::npos)
    {
      std::cout << "gl: " << line << "\n";
    }
  }
  if (calls.empty())
  {
    std::cerr << "BenchVTKRawVolume: no view to render\n";
    return 1;
  }
  const std::vector<double> later(calls.begin() + (calls.size() > 1 ? 1 : 0), calls.end());
  const double median = Median(later);
  std::printf("vtk_raw_volume file=%s steps=%zu povs=%zu size=%dx%d range=%g,%g load_ms=%.1f "
              "first_render_ms=%.1f first_image_ms=%.1f median_render_call_ms=%.3f "
              "p95_render_call_ms=%.3f fps=%.1f\n",
    o.File.c_str(),
    1 + o.MoreFiles.size(),
    calls.size(),
    o.Size,
    o.Size,
    range[0],
    range[1],
    loadMs,
    calls[0],
    loadMs + calls[0],
    median,
    Quantile(later, 0.95),
    median > 0 ? 1e3 / median : 0.0);
  return 0;
}
