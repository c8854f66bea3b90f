// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// Shared pieces of the VTK regression tests: the 49^3 Marschner-Lobb volume on [-1, 1]^3 (Core's
// generator) encoded by vtkAFAMEncoder, the volume property every test uses, and reading the
// window back as RGB bytes.
#ifndef AFAMTestScene_h
#define AFAMTestScene_h

#include "vtkAFAMEncoder.h"
#include "vtkAFAMVolumeMapper.h"

#include "afam/encode/encoder.hpp"

#include "vtkCallbackCommand.h"
#include "vtkCamera.h"
#include "vtkCommand.h"
#include "vtkColorTransferFunction.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkRenderWindow.h"
#include "vtkRenderWindowInteractor.h"
#include "vtkRenderer.h"
#include "vtkSmartPointer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkVolume.h"
#include "vtkVolumeMapper.h"
#include "vtkVolumeProperty.h"
#include "vtkPNGReader.h"
#include "vtkPNGWriter.h"
#include "vtkWindowToImageFilter.h"

#include <algorithm>
#include <cstdlib>
#include <string>

#include <iostream>
#include <vector>

namespace afam_vtk_test
{
/// ML sampled on n^3 over [-1, 1]^3 (point scalars "marschner_lobb").
inline vtkSmartPointer<vtkImageData> MarschnerLobbImage(int n = 49)
{
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(n, n, n);
  image->SetOrigin(-1, -1, -1);
  image->SetSpacing(2.0 / (n - 1), 2.0 / (n - 1), 2.0 / (n - 1));
  vtkNew<vtkFloatArray> values;
  values->SetName("marschner_lobb");
  values->SetNumberOfTuples(static_cast<vtkIdType>(n) * n * n);
  afam::MarschnerLobbSource source(afam::Index3{ n, n, n });
  source.readSlab(0, n, values->GetPointer(0));
  image->GetPointData()->SetScalars(values);
  return image;
}

/// The encoder every test uses: 3 levels, 4 finest blocks per axis, 1% relative RMSE bound.
/// Updated; nullptr (and a message) when encoding failed.
inline vtkSmartPointer<vtkAFAMEncoder> EncodeModels(vtkImageData* image)
{
  auto encoder = vtkSmartPointer<vtkAFAMEncoder>::New();
  encoder->SetInputData(image);
  encoder->SetLevels(3);
  encoder->SetBlocksPerAxis(4);
  encoder->SetErrorBound(0.01);
  encoder->SetRelativeBound(true);
  encoder->Update();
  if (encoder->GetModelFileName()[0] == '\0')
  {
    std::cerr << "encoder produced no model file\n";
    return nullptr;
  }
  return encoder;
}

/// Marschner-Lobb encoded by EncodeModels into a mapper (screen-space LOD policy, finer than the
/// distance bands at these views); `image` gets the sampled volume. nullptr when encoding failed.
inline vtkSmartPointer<vtkAFAMVolumeMapper> MarschnerLobbMapper(
  vtkSmartPointer<vtkImageData>& image)
{
  image = MarschnerLobbImage();
  vtkSmartPointer<vtkAFAMEncoder> encoder = EncodeModels(image);
  if (!encoder)
  {
    return nullptr;
  }
  auto mapper = vtkSmartPointer<vtkAFAMVolumeMapper>::New();
  mapper->SetInputConnection(encoder->GetOutputPort());
  mapper->SetLodPolicyToScreenSpace();
  return mapper;
}

/// Blue-white-red colours, opacity from 0.45 up, unit distance 0.1, unshaded.
inline vtkSmartPointer<vtkVolumeProperty> VolumeProperty()
{
  vtkNew<vtkColorTransferFunction> color;
  color->AddRGBPoint(0.0, 0.05, 0.10, 0.60);
  color->AddRGBPoint(0.5, 0.90, 0.90, 0.90);
  color->AddRGBPoint(1.0, 0.85, 0.20, 0.05);
  vtkNew<vtkPiecewiseFunction> opacity;
  opacity->AddPoint(0.0, 0.0);
  opacity->AddPoint(0.45, 0.0);
  opacity->AddPoint(0.6, 0.1);
  opacity->AddPoint(1.0, 0.4);
  auto property = vtkSmartPointer<vtkVolumeProperty>::New();
  property->SetColor(color);
  property->SetScalarOpacity(opacity);
  property->SetScalarOpacityUnitDistance(0.1);
  property->ShadeOff();
  return property;
}

/// Collects the warning messages `object` emits into `messages` (for as long as the returned
/// command lives).
inline vtkSmartPointer<vtkCallbackCommand> CollectWarnings(vtkObject* object,
  std::vector<std::string>& messages)
{
  auto command = vtkSmartPointer<vtkCallbackCommand>::New();
  command->SetCallback(
    [](vtkObject*, unsigned long, void* clientData, void* callData)
    {
      static_cast<std::vector<std::string>*>(clientData)
        ->push_back(callData ? static_cast<const char*>(callData) : "");
    });
  command->SetClientData(&messages);
  object->AddObserver(vtkCommand::WarningEvent, command);
  return command;
}

/// A vtkVolume drawn by `mapper` with `property`.
inline vtkSmartPointer<vtkVolume> MakeVolume(vtkVolumeMapper* mapper, vtkVolumeProperty* property)
{
  auto volume = vtkSmartPointer<vtkVolume>::New();
  volume->SetMapper(mapper);
  volume->SetProperty(property);
  return volume;
}

/// The tests' window: 301 x 300 (an awkward width), no multisampling, `renderer` in it, an
/// interactor, and the camera at (3.2, 2.4, 4.4) looking at the origin with a 30 degree view.
inline void SetUpWindow(vtkRenderer* renderer,
  vtkRenderWindow* window,
  vtkRenderWindowInteractor* interactor)
{
  window->SetSize(301, 300);
  window->SetMultiSamples(0);
  window->AddRenderer(renderer);
  interactor->SetRenderWindow(window);
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->SetPosition(3.2, 2.4, 4.4);
  camera->SetFocalPoint(0, 0, 0);
  camera->SetViewUp(0, 1, 0);
  camera->SetViewAngle(30);
  renderer->ResetCameraClippingRange();
}

/// The window's current image as RGB bytes (bottom row first).
inline std::vector<unsigned char> ReadPixels(vtkRenderWindow* window)
{
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(window);
  grab->SetInputBufferTypeToRGB();
  grab->ReadFrontBufferOff();
  grab->ShouldRerenderOff();
  grab->Update();
  auto* scalars =
    vtkUnsignedCharArray::SafeDownCast(grab->GetOutput()->GetPointData()->GetScalars());
  const unsigned char* p = scalars ? scalars->GetPointer(0) : nullptr;
  return p ? std::vector<unsigned char>(p, p + scalars->GetNumberOfValues())
           : std::vector<unsigned char>();
}
/// The device the image tests cast on: AFAM_TEST_DEVICE=gpu (the GPU machine,
/// scripts/gpu_vtk_check.sh) asks for the CUDA renderer, and GpuMatchesCpu then fails where it
/// was not used; unset or anything else (CI): the CPU.
inline bool TestOnGpu()
{
  const char* device = std::getenv("AFAM_TEST_DEVICE");
  return device && std::string(device) == "gpu";
}

inline void UseTestDevice(vtkAFAMVolumeMapper* mapper)
{
  mapper->SetRenderDevice(
    TestOnGpu() ? vtkAFAMVolumeMapper::DEVICE_GPU : vtkAFAMVolumeMapper::DEVICE_CPU);
}

/// With AFAM_TEST_DEVICE=gpu: renders a still frame, which `mapper` must have cast on the GPU,
/// then the same frame cast on the CPU; the two must agree within 2/255 on every channel of every
/// pixel. Prints "[vtk gpu-vs-cpu] <what>: ..."; leaves the mapper on the GPU and the GPU frame
/// drawn. Without it: true, nothing done.
inline bool GpuMatchesCpu(vtkRenderWindow* window,
  vtkAFAMVolumeMapper* mapper,
  const std::string& what)
{
  if (!TestOnGpu())
  {
    return true;
  }
  // Twice: a renderer built in a frame (the first after a device change) casts on the GPU but
  // draws through the host; the next goes through CUDA-OpenGL interop where the OpenGL can.
  window->Render();
  window->Render();
  const bool usedGpu = mapper->GetLastUsedGpu();
  const bool onDevice = mapper->GetLastImageOnDevice();
  const std::string interopProblem = mapper->GetLastInteropProblem();
  const std::vector<unsigned char> gpu = ReadPixels(window);
  mapper->SetRenderDeviceToCPU();
  window->Render();
  const std::vector<unsigned char> cpu = ReadPixels(window);
  mapper->SetRenderDeviceToGPU();
  window->Render();
  int worst = 0;
  size_t differing = 0;
  for (size_t i = 0; i < gpu.size() && i < cpu.size(); ++i)
  {
    const int d = std::abs(int(gpu[i]) - int(cpu[i]));
    worst = std::max(worst, d);
    differing += d > 0 ? 1 : 0;
  }
  // AFAM_TEST_INTEROP=1 (the GPU machine, OpenGL on the NVIDIA driver): the GPU frame must also
  // have reached the window without the host.
  const bool needInterop =
    std::getenv("AFAM_TEST_INTEROP") && std::string(std::getenv("AFAM_TEST_INTEROP")) == "1";
  const bool ok =
    usedGpu && (onDevice || !needInterop) && gpu.size() == cpu.size() && !gpu.empty() && worst <= 2;
  std::cout << "[vtk gpu-vs-cpu] " << what << ": cast on the GPU " << usedGpu
            << ", drawn from the GPU (interop) " << onDevice << ", max |diff| " << worst << "/255, "
            << differing << " channel values differ (bar 2/255"
            << (usedGpu ? "" : "; FAILED: the GPU was not used: ") << mapper->GetLastDeviceMessage()
            << (onDevice ? "" : "; interop: " + interopProblem) << ")" << (ok ? "" : " FAILED")
            << "\n";
  return ok;
}

/// vtkTesting's comparison (threshold, neighbourhood averaging) passes smooth volume images drawn
/// a few pixels off or stretched. This one is strict: the fraction of pixels whose largest channel
/// differs from the baseline (the -V argument) by more than `channelTolerance` must stay under
/// `maxFraction`. Prints the figures; false (and why) on a mismatch or an unreadable baseline.
inline bool PixelsMatchBaseline(vtkRenderWindow* window,
  int argc,
  char* argv[],
  int channelTolerance = 24,
  double maxFraction = 0.005)
{
  std::string baseline, outDir;
  for (int i = 0; i + 1 < argc; ++i)
  {
    if (std::string(argv[i]) == "-V")
    {
      baseline = argv[i + 1];
    }
    if (std::string(argv[i]) == "-T")
    {
      outDir = argv[i + 1];
    }
  }
  vtkNew<vtkPNGReader> reader;
  if (baseline.empty() || !reader->CanReadFile(baseline.c_str()))
  {
    std::cerr << "strict comparison: cannot read the baseline '" << baseline << "'\n";
    return false;
  }
  reader->SetFileName(baseline.c_str());
  reader->Update();
  vtkImageData* b = reader->GetOutput();
  auto* bs = vtkUnsignedCharArray::SafeDownCast(b->GetPointData()->GetScalars());
  const int* size = window->GetSize();
  const std::vector<unsigned char> rgb = ReadPixels(window);
  const size_t pixels = static_cast<size_t>(size[0]) * static_cast<size_t>(size[1]);
  if (!bs || bs->GetNumberOfComponents() < 3 || b->GetDimensions()[0] != size[0] ||
    b->GetDimensions()[1] != size[1] || rgb.size() != pixels * 3)
  {
    std::cerr << "strict comparison: baseline " << baseline
              << " is not an RGB image of the window's size\n";
    return false;
  }
  const int nc = bs->GetNumberOfComponents();
  const unsigned char* want = bs->GetPointer(0);
  size_t differing = 0;
  int worst = 0;
  for (size_t i = 0; i < pixels; ++i)
  {
    int d = 0;
    for (int c = 0; c < 3; ++c)
    {
      d = std::max(d, std::abs(int(rgb[3 * i + c]) - int(want[nc * i + c])));
    }
    worst = std::max(worst, d);
    differing += d > channelTolerance ? 1 : 0;
  }
  const double fraction = double(differing) / double(pixels);
  std::cout << "strict comparison: " << differing << " of " << pixels << " pixels ("
            << 100.0 * fraction << " %) differ by more than " << channelTolerance << "/255 (bar "
            << 100.0 * maxFraction << " %); largest difference " << worst << "/255\n";
  if (fraction > maxFraction)
  {
    std::cerr << "strict comparison: the image differs from " << baseline << "\n";
    if (!outDir.empty())
    {
      vtkNew<vtkWindowToImageFilter> grab;
      grab->SetInput(window);
      grab->ReadFrontBufferOff();
      grab->ShouldRerenderOff();
      vtkNew<vtkPNGWriter> writer;
      writer->SetInputConnection(grab->GetOutputPort());
      const std::string name = baseline.substr(baseline.find_last_of('/') + 1);
      writer->SetFileName((outDir + "/strict_" + name).c_str());
      writer->Write();
      std::cerr << "strict comparison: image written to " << outDir << "/strict_" << name << "\n";
    }
    return false;
  }
  return true;
}

/// The scene most tests draw: the Marschner-Lobb mapper cast on the test device (UseTestDevice),
/// VolumeProperty(), the
/// volume in a renderer (background 0.1, 0.1, 0.15) of the tests' window. Ready once Build()
/// returned true (false: encoding failed).
struct Scene
{
  vtkSmartPointer<vtkImageData> Image;
  vtkSmartPointer<vtkAFAMVolumeMapper> Mapper;
  vtkSmartPointer<vtkVolumeProperty> Property;
  vtkSmartPointer<vtkVolume> Volume;
  vtkNew<vtkRenderer> Renderer;
  vtkNew<vtkRenderWindow> Window;
  vtkNew<vtkRenderWindowInteractor> Interactor;

  bool Build()
  {
    this->Mapper = MarschnerLobbMapper(this->Image);
    if (!this->Mapper)
    {
      return false;
    }
    UseTestDevice(this->Mapper);
    this->Property = VolumeProperty();
    this->Volume = MakeVolume(this->Mapper, this->Property);
    this->Renderer->SetBackground(0.1, 0.1, 0.15);
    this->Renderer->AddVolume(this->Volume);
    SetUpWindow(this->Renderer, this->Window, this->Interactor);
    return true;
  }
};
}

#endif
