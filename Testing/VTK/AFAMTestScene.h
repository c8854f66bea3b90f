// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// Shared pieces of the VTK regression tests: the 49^3 Marschner-Lobb volume on [-1, 1]^3 (Core's
// generator) encoded by vtkAFAMEncoder, the volume property every test uses, and reading the
// window back as RGB bytes.
#ifndef AFAMTestScene_h
#define AFAMTestScene_h

#include "vtkAFAMEncoder.h"
#include "vtkAFAMVolumeMapper.h"

#include "afam/encoder.hpp"

#include "vtkColorTransferFunction.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkRenderWindow.h"
#include "vtkSmartPointer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkVolumeProperty.h"
#include "vtkWindowToImageFilter.h"

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
inline vtkSmartPointer<vtkAFAMVolumeMapper> MarschnerLobbMapper(vtkSmartPointer<vtkImageData>& image)
{
  image = MarschnerLobbImage();
  vtkSmartPointer<vtkAFAMEncoder> encoder = EncodeModels(image);
  if (!encoder)
  {
    return nullptr;
  }
  auto mapper = vtkSmartPointer<vtkAFAMVolumeMapper>::New();
  mapper->SetInputConnection(encoder->GetOutputPort());
  mapper->SetLodPolicy(1);
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

/// The window's current image as RGB bytes (bottom row first).
inline std::vector<unsigned char> ReadPixels(vtkRenderWindow* window)
{
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(window);
  grab->SetInputBufferTypeToRGB();
  grab->ReadFrontBufferOff();
  grab->ShouldRerenderOff();
  grab->Update();
  auto* scalars = vtkUnsignedCharArray::SafeDownCast(grab->GetOutput()->GetPointData()->GetScalars());
  const unsigned char* p = scalars ? scalars->GetPointer(0) : nullptr;
  return p ? std::vector<unsigned char>(p, p + scalars->GetNumberOfValues())
           : std::vector<unsigned char>();
}
}

#endif
