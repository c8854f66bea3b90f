// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// Depth compositing of vtkAFAMVolumeMapper with opaque geometry. The 49^3 Marschner-Lobb volume
// ([-1, 1]^3) is seen head-on from +z through a black, unlit, opaque plane that fills the whole
// 301 x 300 window, placed at three depths:
//   z = +1.5 (in front of the volume): the volume must be hidden completely (black image);
//   z = -1.5 (behind it): the whole volume shows over black;
//   z =  0   (cutting it in half): only the front half shows, so the image is dimmer than the
//            whole volume and brighter than nothing; this case is compared with the baseline;
//   z = -0.5 (three quarters of the volume in front): brighter than z = 0, dimmer than all.
// (ML's values are low for z > 0, which this transfer function leaves nearly transparent: the
// front half is much dimmer than the back half.)
// The same in-front case with DepthCompositing off must show the volume, so the test can tell.
// The depth of a pixel becomes a ray length differently under parallel projection (rays start on
// the eye plane) and through the vtkVolume's matrix, so both are checked too: parallel, the plane
// in front hides everything, behind hides nothing, through the middle hides the back half; the
// volume moved to z in [-2, 0] (SetPosition) behind a plane at z = 0.5 is hidden, and a plane at
// its middle (z = -1) hides its back half.
// Usage: TestAFAMDepthCompositing -V <baseline.png> -T <output folder>
#include "AFAMTestScene.h"
#include "vtkAFAMVolumeMapper.h"

#include "vtkActor.h"
#include "vtkCamera.h"
#include "vtkPlaneSource.h"
#include "vtkPolyDataMapper.h"
#include "vtkProperty.h"
#include "vtkRegressionTestImage.h"
#include "vtkRenderWindowInteractor.h"
#include "vtkRenderer.h"
#include "vtkVolume.h"

#include <algorithm>
#include <iostream>
#include <numeric>

namespace
{
struct Shot
{
  double sum = 0; // sum of all RGB bytes
  int max = 0;    // brightest byte
  vtkTypeInt64 limited = 0;
};

Shot Take(vtkRenderWindow* window,
  vtkRenderer* renderer,
  vtkPlaneSource* plane,
  vtkAFAMVolumeMapper* mapper,
  double z)
{
  plane->SetOrigin(-3, -3, z);
  plane->SetPoint1(3, -3, z);
  plane->SetPoint2(-3, 3, z);
  renderer->ResetCameraClippingRange();
  window->Render();
  const std::vector<unsigned char> rgb = afam_vtk_test::ReadPixels(window);
  Shot s;
  s.sum = std::accumulate(rgb.begin(), rgb.end(), 0.0);
  s.max = rgb.empty() ? -1 : *std::max_element(rgb.begin(), rgb.end());
  s.limited = mapper->GetLastDepthLimitedPixels();
  return s;
}
}

int TestAFAMDepthCompositing(int argc, char* argv[])
{
  vtkSmartPointer<vtkImageData> image;
  vtkSmartPointer<vtkAFAMVolumeMapper> mapper = afam_vtk_test::MarschnerLobbMapper(image);
  if (!mapper)
  {
    return EXIT_FAILURE;
  }
  afam_vtk_test::UseTestDevice(mapper);
  vtkNew<vtkVolume> volume;
  volume->SetMapper(mapper);
  volume->SetProperty(afam_vtk_test::VolumeProperty());

  vtkNew<vtkPlaneSource> plane;
  vtkNew<vtkPolyDataMapper> planeMapper;
  planeMapper->SetInputConnection(plane->GetOutputPort());
  vtkNew<vtkActor> planeActor;
  planeActor->SetMapper(planeMapper);
  planeActor->GetProperty()->SetColor(0, 0, 0);
  planeActor->GetProperty()->LightingOff();

  vtkNew<vtkRenderer> renderer;
  renderer->SetBackground(0.1, 0.1, 0.15);
  renderer->AddActor(planeActor);
  renderer->AddVolume(volume);
  vtkNew<vtkRenderWindow> window;
  const int width = 301, height = 300;
  window->SetSize(width, height);
  window->SetMultiSamples(0);
  window->AddRenderer(renderer);
  vtkNew<vtkRenderWindowInteractor> interactor;
  interactor->SetRenderWindow(window);
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->SetPosition(0.3, 0.2, 5.0);
  camera->SetFocalPoint(0, 0, 0);
  camera->SetViewUp(0, 1, 0);
  camera->SetViewAngle(30);

  const Shot front = Take(window, renderer, plane, mapper, 1.5);
  const Shot back = Take(window, renderer, plane, mapper, -1.5);
  mapper->DepthCompositingOff();
  const Shot frontIgnored = Take(window, renderer, plane, mapper, 1.5);
  mapper->DepthCompositingOn();
  const Shot quarter = Take(window, renderer, plane, mapper, -0.5);
  camera->ParallelProjectionOn();
  camera->SetParallelScale(1.4);
  const Shot parallelFront = Take(window, renderer, plane, mapper, 1.5);
  const Shot parallelBack = Take(window, renderer, plane, mapper, -1.5);
  const Shot parallelMiddle = Take(window, renderer, plane, mapper, 0.0);
  camera->ParallelProjectionOff();
  volume->SetPosition(0, 0, -1);
  const Shot movedFront = Take(window, renderer, plane, mapper, 0.5);
  const Shot movedBack = Take(window, renderer, plane, mapper, -2.5);
  const Shot movedMiddle = Take(window, renderer, plane, mapper, -1.0);
  volume->SetPosition(0, 0, 0);
  const Shot middle = Take(window, renderer, plane, mapper, 0.0);

  const vtkTypeInt64 pixels = static_cast<vtkTypeInt64>(width) * height;
  std::cout << "sum of RGB bytes: plane in front " << front.sum << " (max " << front.max
            << "), behind " << back.sum << ", through the middle " << middle.sum << ", at z = -0.5 "
            << quarter.sum << ", in front without depth compositing " << frontIgnored.sum
            << "; depth-limited pixels " << front.limited << " / " << back.limited << " / "
            << middle.limited << " / " << frontIgnored.limited << " of " << pixels << "\n";
  int failures = 0;
  auto check = [&failures](bool ok, const char* what)
  {
    if (!ok)
    {
      std::cerr << "FAILED: " << what << "\n";
      ++failures;
    }
  };
  check(front.limited == pixels && back.limited == pixels && middle.limited == pixels,
    "every pixel's ray is limited by the plane");
  check(frontIgnored.limited == 0, "depth compositing off reads no depth");
  check(front.max <= 1, "plane in front: the volume is hidden (image black)");
  check(back.sum > 1e5, "plane behind: the volume shows");
  check(frontIgnored.sum > 0.9 * back.sum, "depth compositing off: the volume shows in front");
  check(middle.sum > 0.01 * back.sum && middle.sum < 0.5 * back.sum,
    "plane through the middle: only the front part of the volume shows");
  check(quarter.sum > 1.5 * middle.sum && quarter.sum < 0.9 * back.sum,
    "plane at z = -0.5: more of the volume than at z = 0, less than all of it");
  std::cout << "parallel projection: in front " << parallelFront.sum << " (max "
            << parallelFront.max << "), behind " << parallelBack.sum << ", middle "
            << parallelMiddle.sum << "; moved to z in [-2, 0]: in front " << movedFront.sum
            << " (max " << movedFront.max << "), behind " << movedBack.sum << ", middle "
            << movedMiddle.sum << "\n";
  check(parallelFront.limited == pixels && parallelFront.max <= 1,
    "parallel projection, plane in front: the volume is hidden");
  check(parallelBack.sum > 1e5, "parallel projection, plane behind: the volume shows");
  check(parallelMiddle.sum > 0.01 * parallelBack.sum && parallelMiddle.sum < 0.5 * parallelBack.sum,
    "parallel projection, plane through the middle: only the front part shows");
  check(movedFront.max <= 1, "moved volume, plane in front: hidden");
  check(movedBack.sum > 1e5, "moved volume, plane behind: it shows");
  check(movedMiddle.sum > 0.01 * movedBack.sum && movedMiddle.sum < 0.5 * movedBack.sum,
    "moved volume, plane through its middle: only its front part shows");

  // Nothing visible but the volume: no opaque geometry can have written depth, so none is read.
  planeActor->VisibilityOff();
  window->Render();
  const double aloneRead = mapper->GetLastDepthReadTime();
  const vtkTypeInt64 aloneLimited = mapper->GetLastDepthLimitedPixels();
  planeActor->VisibilityOn();
  window->Render();
  std::cout << "depth read: " << 1e3 * aloneRead << " ms with the volume alone, "
            << 1e3 * mapper->GetLastDepthReadTime() << " ms with the plane\n";
  check(aloneRead == 0 && aloneLimited == 0, "the volume alone: the depth buffer is not read");
  check(mapper->GetLastDepthReadTime() > 0 && mapper->GetLastDepthLimitedPixels() == pixels,
    "with the plane visible again: the depth buffer is read");
  check(afam_vtk_test::GpuMatchesCpu(window, mapper, "DepthCompositing, last view"),
    "GPU frame equals the CPU frame");
  const int result = vtkRegressionTestImageThreshold(window, 15);
  if (result == vtkRegressionTester::DO_INTERACTOR)
  {
    interactor->Start();
  }
  const bool placed = afam_vtk_test::PixelsMatchBaseline(window, argc, argv);
  return (failures == 0 && placed && result == vtkRegressionTester::PASSED) ? EXIT_SUCCESS
                                                                            : EXIT_FAILURE;
}

int main(int argc, char* argv[])
{
  return TestAFAMDepthCompositing(argc, argv);
}
