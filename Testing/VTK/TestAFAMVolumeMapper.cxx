// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// Regression image test of vtkAFAMVolumeMapper: a 49^3 Marschner-Lobb volume (Core's generator)
// encoded with vtkAFAMEncoder and rendered out of core in an awkward 301 x 300 window, blended
// over an opaque sphere that sticks out of the volume.
// Usage: TestAFAMVolumeMapper -V <baseline.png> -T <output folder>
#include "vtkAFAMEncoder.h"
#include "vtkAFAMVolumeMapper.h"

#include "afam/encoder.hpp"

#include "vtkActor.h"
#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkOutlineFilter.h"
#include "vtkProperty.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkPolyDataMapper.h"
#include "vtkRegressionTestImage.h"
#include "vtkRenderWindow.h"
#include "vtkRenderWindowInteractor.h"
#include "vtkRenderer.h"
#include "vtkSphereSource.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <iostream>

int TestAFAMVolumeMapper(int argc, char* argv[])
{
  const int n = 49;
  vtkNew<vtkImageData> image;
  image->SetDimensions(n, n, n);
  image->SetOrigin(-1, -1, -1);
  image->SetSpacing(2.0 / (n - 1), 2.0 / (n - 1), 2.0 / (n - 1));
  vtkNew<vtkFloatArray> values;
  values->SetName("marschner_lobb");
  values->SetNumberOfTuples(static_cast<vtkIdType>(n) * n * n);
  afam::MarschnerLobbSource source(afam::Index3{ n, n, n });
  source.readSlab(0, n, values->GetPointer(0));
  image->GetPointData()->SetScalars(values);

  vtkNew<vtkAFAMEncoder> encoder;
  encoder->SetInputData(image);
  encoder->SetLevels(3);
  encoder->SetBlocksPerAxis(4);
  encoder->SetErrorBound(0.01);
  encoder->SetRelativeBound(true);
  encoder->Update();
  if (encoder->GetModelFileName()[0] == '\0')
  {
    std::cerr << "encoder produced no model file\n";
    return EXIT_FAILURE;
  }

  vtkNew<vtkAFAMVolumeMapper> mapper;
  mapper->SetInputConnection(encoder->GetOutputPort());
  mapper->SetLodPolicy(1); // screen-space error: finer levels at this distance than the bands

  vtkNew<vtkColorTransferFunction> color;
  color->AddRGBPoint(0.0, 0.05, 0.10, 0.60);
  color->AddRGBPoint(0.5, 0.90, 0.90, 0.90);
  color->AddRGBPoint(1.0, 0.85, 0.20, 0.05);
  vtkNew<vtkPiecewiseFunction> opacity;
  opacity->AddPoint(0.0, 0.0);
  opacity->AddPoint(0.45, 0.0);
  opacity->AddPoint(0.6, 0.1);
  opacity->AddPoint(1.0, 0.4);
  vtkNew<vtkVolumeProperty> property;
  property->SetColor(color);
  property->SetScalarOpacity(opacity);
  property->SetScalarOpacityUnitDistance(0.1);
  property->ShadeOff();

  vtkNew<vtkVolume> volume;
  volume->SetMapper(mapper);
  volume->SetProperty(property);

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
  window->SetSize(301, 300);
  window->SetMultiSamples(0);
  window->AddRenderer(renderer);
  vtkNew<vtkRenderWindowInteractor> interactor;
  interactor->SetRenderWindow(window);

  vtkCamera* camera = renderer->GetActiveCamera();
  camera->SetPosition(3.2, 2.4, 4.4);
  camera->SetFocalPoint(0, 0, 0);
  camera->SetViewUp(0, 1, 0);
  camera->SetViewAngle(30);
  renderer->ResetCameraClippingRange();
  window->Render();

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

  const int result = vtkRegressionTestImageThreshold(window, 15);
  if (result == vtkRegressionTester::DO_INTERACTOR)
  {
    interactor->Start();
  }
  return result == vtkRegressionTester::PASSED ? EXIT_SUCCESS : EXIT_FAILURE;
}

int main(int argc, char* argv[])
{
  return TestAFAMVolumeMapper(argc, argv);
}
