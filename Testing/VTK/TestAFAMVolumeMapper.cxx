// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// Regression image test of vtkAFAMVolumeMapper: a 49^3 Marschner-Lobb volume (Core's generator)
// encoded with vtkAFAMEncoder and rendered out of core in an awkward 301 x 300 window, over an
// opaque sphere that sticks out of the volume.
// Usage: TestAFAMVolumeMapper [--device gpu] -V <baseline.png> -T <output folder>
//   default: RenderDevice Auto, no warning may be issued;
//   --device gpu: RenderDevice GPU. Where the CUDA renderer is unusable (built without CUDA, no
//   GPU or driver) exactly one warning must say so across two frames and the frames must be cast
//   on the CPU; where it is usable the frames must be cast on the GPU without a warning. Either
//   way the image must match the same baseline.
// AFAM_TEST_DEVICE=gpu: as --device gpu, and the frames must be cast on the GPU and equal the CPU's
// within 2/255 (afam_vtk_test::GpuMatchesCpu).
// Interactive frames (DesiredUpdateRate 1e5, a 10 us budget) must be cast at the minimum image
// scale, faster, and show the same picture (mean difference under 8/255 per channel against
// the still frame); the next still frame is full size again (and is the one compared with the
// baseline).
#include "AFAMTestScene.h"
#include "vtkAFAMVolumeMapper.h"

#include "vtkActor.h"
#include "vtkCallbackCommand.h"
#include "vtkCamera.h"
#include "vtkCommand.h"
#include "vtkOutlineFilter.h"
#include "vtkPolyDataMapper.h"
#include "vtkProperty.h"
#include "vtkRegressionTestImage.h"
#include "vtkRenderWindowInteractor.h"
#include "vtkRenderer.h"
#include "vtkSphereSource.h"
#include "vtkVolume.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iostream>
#include <string>
#include <vector>

int TestAFAMVolumeMapper(int argc, char* argv[])
{
  bool gpu = afam_vtk_test::TestOnGpu();
  for (int i = 1; i + 1 < argc; ++i)
  {
    if (std::strcmp(argv[i], "--device") == 0)
    {
      gpu = gpu || std::strcmp(argv[i + 1], "gpu") == 0;
    }
  }
  vtkSmartPointer<vtkImageData> image;
  vtkSmartPointer<vtkAFAMVolumeMapper> mapper = afam_vtk_test::MarschnerLobbMapper(image);
  if (!mapper)
  {
    return EXIT_FAILURE;
  }
  mapper->SetRenderDevice(gpu ? vtkAFAMVolumeMapper::DEVICE_GPU : vtkAFAMVolumeMapper::DEVICE_AUTO);
  std::vector<std::string> warnings;
  auto watch = afam_vtk_test::CollectWarnings(mapper, warnings);
  vtkSmartPointer<vtkVolumeProperty> property = afam_vtk_test::VolumeProperty();
  vtkSmartPointer<vtkVolume> volume = afam_vtk_test::MakeVolume(mapper, property);

  vtkNew<vtkSphereSource> sphere;
  sphere->SetCenter(-1.3, 0.0, 0.6);
  sphere->SetRadius(0.3);
  sphere->SetThetaResolution(32);
  sphere->SetPhiResolution(32);
  vtkNew<vtkPolyDataMapper> sphereMapper;
  sphereMapper->SetInputConnection(sphere->GetOutputPort());
  vtkNew<vtkActor> sphereActor;
  sphereActor->SetMapper(sphereMapper);

  // The volume's box as opaque lines: shows that the ray-cast image lines up with VTK's camera.
  vtkNew<vtkOutlineFilter> outline;
  outline->SetInputData(image);
  vtkNew<vtkPolyDataMapper> outlineMapper;
  outlineMapper->SetInputConnection(outline->GetOutputPort());
  vtkNew<vtkActor> outlineActor;
  outlineActor->SetMapper(outlineMapper);
  outlineActor->GetProperty()->SetColor(1, 1, 0);

  vtkNew<vtkRenderer> renderer;
  renderer->AddActor(outlineActor);
  renderer->SetBackground(0.1, 0.1, 0.15);
  renderer->AddActor(sphereActor);
  renderer->AddVolume(volume);
  vtkNew<vtkRenderWindow> window;
  vtkNew<vtkRenderWindowInteractor> interactor;
  afam_vtk_test::SetUpWindow(renderer, window, interactor);
  window->Render();
  window->Render(); // a second frame: a fallback warning must not repeat

  std::cout << "frames " << mapper->GetNumberOfFrames() << " total " << mapper->GetLastTotalTime()
            << " s, ray cast " << mapper->GetLastRenderTime() << " s, caching "
            << mapper->GetLastCachingTime() << " s, visible " << mapper->GetLastVisibleBlocks()
            << ", culled " << mapper->GetLastCulledBlocks() << ", misses "
            << mapper->GetLastCacheMisses() << "\n";
  if (mapper->GetNumberOfFrames() < 1 || mapper->GetLastVisibleBlocks() < 1)
  {
    std::cerr << "the mapper did not render\n";
    return EXIT_FAILURE;
  }

  std::cout << "device " << (gpu ? "gpu" : "auto") << ": CUDA renderer built "
            << vtkAFAMVolumeMapper::HasCudaRenderer() << ", last frame on the GPU "
            << mapper->GetLastUsedGpu() << ", warnings " << warnings.size() << ", message '"
            << mapper->GetLastDeviceMessage() << "'\n";
  for (const std::string& w : warnings)
  {
    std::cout << "warning: " << w << "\n";
  }
  if (afam_vtk_test::TestOnGpu() && !mapper->GetLastUsedGpu())
  {
    std::cerr << "AFAM_TEST_DEVICE=gpu and the frame was cast on the CPU: "
              << mapper->GetLastDeviceMessage() << "\n";
    return EXIT_FAILURE;
  }
  if (gpu && !mapper->GetLastUsedGpu())
  {
    if (warnings.size() != 1 || warnings[0].find("CPU") == std::string::npos ||
      std::string(mapper->GetLastDeviceMessage()).empty())
    {
      std::cerr << "GPU asked for and unusable: expected exactly one warning naming the CPU "
                   "fallback and a device message\n";
      return EXIT_FAILURE;
    }
  }
  else if (!warnings.empty())
  {
    std::cerr << "unexpected warnings\n";
    return EXIT_FAILURE;
  }
  if (!vtkAFAMVolumeMapper::HasCudaRenderer() && mapper->GetLastUsedGpu())
  {
    std::cerr << "a build without CUDA claims to have rendered on the GPU\n";
    return EXIT_FAILURE;
  }

  // Interactive frames, then a still frame again.
  const std::vector<unsigned char> still = afam_vtk_test::ReadPixels(window);
  const double stillSeconds = mapper->GetLastRenderTime() + mapper->GetLastCachingTime();
  window->SetDesiredUpdateRate(1e5); // a 10 us budget: the minimum scale on a GPU too
  window->Render();
  window->Render();
  const double interactiveScale = mapper->GetLastImageScale();
  const double interactiveSeconds = mapper->GetLastRenderTime() + mapper->GetLastCachingTime();
  const std::vector<unsigned char> moving = afam_vtk_test::ReadPixels(window);
  double meanDiff = 0;
  for (size_t i = 0; i < still.size() && i < moving.size(); ++i)
  {
    meanDiff += std::abs(int(still[i]) - int(moving[i]));
  }
  meanDiff /= std::max<size_t>(1, still.size());
  window->SetDesiredUpdateRate(0.0001);
  window->Render();
  std::cout << "interactive frames: image scale " << interactiveScale << ", cast in "
            << interactiveSeconds << " s against " << stillSeconds
            << " s still; mean |interactive - still| " << meanDiff
            << "/255 per channel; next still frame at scale " << mapper->GetLastImageScale()
            << "\n";
  // (The time check is for the CPU caster, whose time scales with pixels; a GPU frame this small
  // is dominated by fixed costs.)
  const bool slower = !mapper->GetLastUsedGpu() && interactiveSeconds >= 0.6 * stillSeconds;
  if (std::abs(interactiveScale - 75.0 / 301.0) > 1e-9 || slower || moving.size() != still.size() ||
    meanDiff > 8.0 || mapper->GetLastImageScale() != 1.0)
  {
    std::cerr << "interactive image scaling: expected scale 75/301 (the minimum 0.25), a faster "
                 "frame, the same picture, and full size again when still\n";
    return EXIT_FAILURE;
  }

  if (!afam_vtk_test::GpuMatchesCpu(window, mapper, "VolumeMapper, still frame"))
  {
    return EXIT_FAILURE;
  }
  const int result = vtkRegressionTestImageThreshold(window, 15);
  if (result == vtkRegressionTester::DO_INTERACTOR)
  {
    interactor->Start();
  }
  const bool placed = afam_vtk_test::PixelsMatchBaseline(window, argc, argv);
  return result == vtkRegressionTester::PASSED && placed ? EXIT_SUCCESS : EXIT_FAILURE;
}

int main(int argc, char* argv[])
{
  return TestAFAMVolumeMapper(argc, argv);
}
