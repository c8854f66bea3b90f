// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// vtkAFAMVolumeMapper on a masked file: Marschner-Lobb 49^3 whose samples at x >= 30 are NaN (the
// finest blocks there masked or empty), encoded by vtkAFAMEncoder and seen straight down z
// (parallel projection, 301 x 300). "Draw NaN" off (DrawMissingValues, the default): pixels whose
// rays cross only missing samples (5 voxels clear of the boundary, so that every level's majority
// mask agrees) are the background exactly. On, with NanColor (0.2, 0.9, 0.3) and NanOpacity 1: the
// same pixels are the NaN colour, and pixels whose rays cross only valid samples are unchanged.
// Usage: TestAFAMMissingDraw
#include "AFAMTestScene.h"
#include "vtkAFAMVolumeMapper.h"

#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkRenderWindowInteractor.h"
#include "vtkRenderer.h"

#include <cmath>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

namespace
{
const int N = 49, Width = 301, Height = 300;
const double ParallelScale = 1.05;
const int Margin = 5;         // voxels: the coarsest level's stride (4) and one more
const int FirstMissingX = 30; // samples at x >= 30 are missing

int failures = 0;

void Check(bool ok, const std::string& what)
{
  std::cout << (ok ? "ok: " : "FAILED: ") << what << "\n";
  failures += ok ? 0 : 1;
}

/// Marschner-Lobb with NaN at x >= FirstMissingX.
vtkSmartPointer<vtkImageData> MaskedImage()
{
  vtkSmartPointer<vtkImageData> image = afam_vtk_test::MarschnerLobbImage(N);
  auto* values = vtkFloatArray::SafeDownCast(image->GetPointData()->GetScalars());
  for (vtkIdType i = 0; i < values->GetNumberOfTuples(); ++i)
  {
    if (i % N >= FirstMissingX)
    {
      values->SetValue(i, std::numeric_limits<float>::quiet_NaN());
    }
  }
  return image;
}

/// What every column within Margin voxels of a pixel's ray holds: 1 only missing samples, 2 only
/// valid ones, 0 both or outside the volume.
int Columns(int px, int py)
{
  const double unit = 2 * ParallelScale / Height; // world units a pixel
  const double wx = (px + 0.5 - Width / 2.0) * unit, wy = (py + 0.5 - Height / 2.0) * unit;
  const double vx = (wx + 1) * (N - 1) / 2, vy = (wy + 1) * (N - 1) / 2; // voxel coordinates
  if (vx < 0.5 || vy < 0.5 || vx > N - 1.5 || vy > N - 1.5)
  {
    return 0;
  }
  const int x = static_cast<int>(vx);
  return x - Margin >= FirstMissingX ? 1 : x + 1 + Margin < FirstMissingX ? 2 : 0;
}

bool Near(const unsigned char* a, const double rgb[3], int tolerance)
{
  for (int c = 0; c < 3; ++c)
  {
    if (std::abs(a[c] - static_cast<int>(std::lround(255 * rgb[c]))) > tolerance)
    {
      return false;
    }
  }
  return true;
}
}

int main(int, char*[])
{
  vtkSmartPointer<vtkAFAMEncoder> encoder = afam_vtk_test::EncodeModels(MaskedImage());
  if (!encoder)
  {
    return EXIT_FAILURE;
  }
  vtkNew<vtkAFAMVolumeMapper> mapper;
  mapper->SetInputConnection(encoder->GetOutputPort());
  mapper->SetLodPolicyToScreenSpace();
  vtkSmartPointer<vtkVolumeProperty> property = afam_vtk_test::VolumeProperty();
  const double nanColor[3] = { 0.2, 0.9, 0.3 }, background[3] = { 0.1, 0.1, 0.15 };
  auto* color = vtkColorTransferFunction::SafeDownCast(property->GetRGBTransferFunction());
  color->SetNanColor(nanColor[0], nanColor[1], nanColor[2]);
  color->SetNanOpacity(1.0);
  vtkNew<vtkRenderer> renderer;
  renderer->SetBackground(background[0], background[1], background[2]);
  renderer->AddVolume(afam_vtk_test::MakeVolume(mapper, property));
  vtkNew<vtkRenderWindow> window;
  vtkNew<vtkRenderWindowInteractor> interactor;
  afam_vtk_test::SetUpWindow(renderer, window, interactor);
  window->SetSize(Width, Height);
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->SetPosition(0, 0, 5);
  camera->SetFocalPoint(0, 0, 0);
  camera->SetViewUp(0, 1, 0);
  camera->ParallelProjectionOn();
  camera->SetParallelScale(ParallelScale);
  renderer->ResetCameraClippingRange();

  window->Render();
  const std::vector<unsigned char> off = afam_vtk_test::ReadPixels(window);
  mapper->DrawMissingValuesOn();
  window->Render();
  const std::vector<unsigned char> on = afam_vtk_test::ReadPixels(window);
  if (off.size() != static_cast<size_t>(3 * Width * Height) || on.size() != off.size())
  {
    std::cerr << "could not read the window's pixels\n";
    return EXIT_FAILURE;
  }
  int missingOnly = 0, validOnly = 0, offNotBackground = 0, onNotNan = 0, validChanged = 0,
      validDrawn = 0;
  for (int py = 0; py < Height; ++py)
    for (int px = 0; px < Width; ++px)
    {
      const size_t p = 3 * (static_cast<size_t>(py) * Width + px);
      const int kind = Columns(px, py);
      missingOnly += kind == 1;
      validOnly += kind == 2;
      offNotBackground += kind == 1 && !Near(&off[p], background, 1);
      onNotNan += kind == 1 && !Near(&on[p], nanColor, 2);
      bool same = true;
      for (int c = 0; c < 3; ++c)
      {
        same = same && std::abs(on[p + c] - off[p + c]) <= 1;
      }
      validChanged += kind == 2 && !same;
      validDrawn += kind == 2 && !Near(&off[p], background, 8);
    }
  std::cout << "missing-only pixels " << missingOnly
            << " (not background with Draw NaN off: " << offNotBackground
            << ", not the NaN colour with it on: " << onNotNan << "); valid-only pixels "
            << validOnly << " (drawn " << validDrawn << ", changed by Draw NaN " << validChanged
            << ")\n";
  Check(missingOnly > 5000, "the right of the image sees only missing samples");
  Check(offNotBackground == 0, "Draw NaN off: rays through missing samples only stay background");
  Check(onNotNan == 0, "Draw NaN on, NaN opacity 1: those rays are the NaN colour");
  Check(validOnly > 5000 && validDrawn > validOnly / 4, "the valid region is drawn");
  Check(validChanged == 0, "Draw NaN changes no ray that crosses only valid samples");
  std::cout << failures << " failure(s)\n";
  return failures == 0 ? EXIT_SUCCESS : EXIT_FAILURE;
}
