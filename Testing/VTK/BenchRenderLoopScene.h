// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// What the render-loop benchmarks share (BenchAFAMRenderLoop on .afam files, BenchVTKRawVolume on
// raw volumes with VTK's own GPU ray caster): `afam replay`'s cameras and transfer function as VTK
// objects, and the statistics they print.
#ifndef BenchRenderLoopScene_h
#define BenchRenderLoopScene_h

#include "afam/scene/camera.hpp"
#include "afam/scene/transfer_function.hpp"

#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkNew.h"
#include "vtkPiecewiseFunction.h"
#include "vtkVolumeProperty.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace
{
double Median(std::vector<double> v)
{
  if (v.empty())
  {
    return 0;
  }
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The q-quantile (0..1) of v, nearest rank.
double Quantile(std::vector<double> v, double q)
{
  if (v.empty())
  {
    return 0;
  }
  std::sort(v.begin(), v.end());
  const size_t rank = static_cast<size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, rank > 0 ? rank - 1 : 0)];
}

// The VTK camera that casts Core's rays for `pose`: the normalised frame [-1, 1]^3 is the data box
// (centre `c`, half extents `h`), so the eye maps by c + h * eye and the view angle is Core's.
void PlaceCamera(vtkCamera* camera,
  const afam::Pose& pose,
  const double c[3],
  const double h[3],
  int size)
{
  const afam::Camera core = afam::Camera::fromPose(pose, size, size);
  double eye[3], focal[3];
  for (int a = 0; a < 3; ++a)
  {
    eye[a] = c[a] + h[a] * core.eye[a];
    focal[a] = c[a] + h[a] * (core.eye[a] + core.forward[a]);
  }
  camera->SetPosition(eye);
  camera->SetFocalPoint(focal);
  camera->SetViewUp(core.up[0], core.up[1], core.up[2]);
  camera->SetViewAngle(2.0 * std::atan(core.tanHalfY) * 180.0 / 3.14159265358979323846);
}

// Core's preset transfer function over [lo, hi] as VTK functions; the opacity unit distance in
// world units (`unit` = world length of one normalised unit).
void SetPresetTransferFunction(vtkVolumeProperty* property, double lo, double hi, double unit)
{
  const afam::TransferFunction tf = afam::TransferFunction::preset(lo, hi);
  vtkNew<vtkColorTransferFunction> color;
  for (const auto& p : tf.colors)
  {
    color->AddRGBPoint(p.value, p.r, p.g, p.b);
  }
  vtkNew<vtkPiecewiseFunction> opacity;
  for (const auto& p : tf.opacities)
  {
    opacity->AddPoint(p.value, p.alpha);
  }
  property->SetColor(color);
  property->SetScalarOpacity(opacity);
  property->SetScalarOpacityUnitDistance(tf.referenceDistance * unit);
  property->ShadeOn();
}

}

#endif
