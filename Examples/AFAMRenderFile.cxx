// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// The README's plain-VTK example as a program: reads an .afam file and renders it in a window.
//   AFAMRenderFile <file.afam>            an interactive window (close it to quit)
//   AFAMRenderFile <file.afam> --check    one frame, no interaction; fails unless the volume
//                                         covers at least 5% of the window (the example's test)
// The lines between the two "README" markers are the README's example, word for word (the test
// AFAM.Example.ReadmeMatches compares them).
#include "vtkAFAMReader.h"
#include "vtkAFAMVolumeMapper.h"

#include "vtkColorTransferFunction.h"
#include "vtkNew.h"
#include "vtkPiecewiseFunction.h"
#include "vtkRenderWindow.h"
#include "vtkRenderWindowInteractor.h"
#include "vtkRenderer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <cstdlib>
#include <cstring>
#include <iostream>

namespace
{
// Fraction of the window's pixels that differ from the black background.
double CoveredFraction(vtkRenderWindow* window)
{
  const int* size = window->GetSize();
  vtkNew<vtkUnsignedCharArray> rgb;
  window->GetPixelData(0, 0, size[0] - 1, size[1] - 1, /*front=*/0, rgb);
  vtkIdType covered = 0;
  for (vtkIdType i = 0; i < rgb->GetNumberOfTuples(); ++i)
  {
    covered += rgb->GetValue(3 * i) + rgb->GetValue(3 * i + 1) + rgb->GetValue(3 * i + 2) > 6;
  }
  return static_cast<double>(covered) / static_cast<double>(size[0] * size[1]);
}
}

int main(int argc, char* argv[])
{
  if (argc < 2 || (argc > 2 && std::strcmp(argv[2], "--check") != 0))
  {
    std::cerr << "usage: AFAMRenderFile <file.afam> [--check]\n";
    return EXIT_FAILURE;
  }
  const char* path = argv[1];
  // README begin
  vtkNew<vtkAFAMReader> reader; // the file's micro-models, streamed on demand
  reader->SetFileName(path);
  vtkNew<vtkAFAMVolumeMapper> mapper; // ray casts the splines (CUDA when built with it, else CPU)
  mapper->SetInputConnection(reader->GetOutputPort());
  vtkNew<vtkColorTransferFunction> color; // the usual VTK transfer functions
  color->AddRGBPoint(0.0, 0.1, 0.2, 0.8);
  color->AddRGBPoint(1.0, 1.0, 0.6, 0.1);
  vtkNew<vtkPiecewiseFunction> opacity;
  opacity->AddPoint(0.3, 0.0);
  opacity->AddPoint(1.0, 0.6);
  vtkNew<vtkVolume> volume;
  volume->SetMapper(mapper);
  volume->GetProperty()->SetColor(color);
  volume->GetProperty()->SetScalarOpacity(opacity);
  vtkNew<vtkRenderer> renderer;
  renderer->AddVolume(volume);
  vtkNew<vtkRenderWindow> window;
  window->AddRenderer(renderer);
  vtkNew<vtkRenderWindowInteractor> interactor;
  interactor->SetRenderWindow(window);
  window->Render();
  // README end
  if (argc > 2)
  {
    const double covered = CoveredFraction(window);
    std::cout << "frames drawn " << mapper->GetNumberOfFrames() << ", visible micro-models "
              << mapper->GetLastVisibleBlocks() << ", window covered " << 100.0 * covered << " %\n";
    return mapper->GetNumberOfFrames() >= 1 && covered >= 0.05 ? EXIT_SUCCESS : EXIT_FAILURE;
  }
  interactor->Start();
  return EXIT_SUCCESS;
}
