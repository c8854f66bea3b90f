// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// Plain VTK: a vtkAFAMVolumeMapper given only a FileName (no input connection) draws the volume,
// the same picture as the mapper fed by the encoder's output, and its bounds follow the name.
// Usage: TestAFAMMapperFileName
#include "AFAMTestScene.h"
#include "vtkAFAMVolumeMapper.h"

#include "vtkMath.h"
#include "vtkRenderWindowInteractor.h"
#include "vtkRenderer.h"

#include <cstdlib>
#include <iostream>

int main(int, char*[])
{
  afam_vtk_test::Scene scene;
  if (!scene.Build())
  {
    return EXIT_FAILURE;
  }
  vtkAFAMVolumeMapper* connected = scene.Mapper;
  vtkRenderWindow* window = scene.Window;
  window->Render();
  const std::vector<unsigned char> expected = afam_vtk_test::ReadPixels(window);

  // The same file through FileName alone.
  connected->Update(); // the encoder has run: its model file exists
  const std::string file = connected->GetInputAlgorithm()
    ? static_cast<vtkAFAMEncoder*>(connected->GetInputAlgorithm())->GetModelFileName()
    : "";
  vtkNew<vtkAFAMVolumeMapper> alone;
  alone->SetFileName(file.c_str());
  alone->SetLodPolicyToScreenSpace();
  afam_vtk_test::UseTestDevice(alone);
  scene.Volume->SetMapper(alone);
  window->Render();
  const std::vector<unsigned char> got = afam_vtk_test::ReadPixels(window);
  long differing = 0, foreground = 0;
  for (size_t i = 0; i + 2 < got.size() && i + 2 < expected.size(); i += 3)
  {
    differing +=
      (got[i] != expected[i] || got[i + 1] != expected[i + 1] || got[i + 2] != expected[i + 2]) ? 1
                                                                                                : 0;
    foreground += (std::abs(got[i] - 26) > 8 || std::abs(got[i + 2] - 38) > 8) ? 1 : 0;
  }
  std::cout << "FileName only (" << file << "): " << alone->GetNumberOfFrames() << " frame(s), "
            << foreground << " foreground pixels, " << differing
            << " pixels differ from the connected mapper's image\n";
  // Bounds follow FileName: another name is opened (here none can be), not the old file kept.
  const bool hadBounds = vtkMath::AreBoundsInitialized(alone->GetBounds());
  alone->SetFileName((file + ".gone").c_str());
  const bool renamedBounds = vtkMath::AreBoundsInitialized(alone->GetBounds());
  std::cout << "bounds with the file: " << hadBounds << ", after naming a missing one "
            << renamedBounds << "\n";
  alone->SetFileName(file.c_str());
  const bool ok = alone->GetNumberOfFrames() >= 1 && foreground > 1000 && differing == 0 &&
    hadBounds && !renamedBounds &&
    afam_vtk_test::GpuMatchesCpu(window, alone, "MapperFileName, FileName only");
  std::cout << (ok ? "ok" : "FAILED") << "\n";
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
