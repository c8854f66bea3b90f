// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// What the render-loop benchmarks share (BenchAFAMRenderLoop on .afam files, BenchVTKRawVolume on
// raw volumes with VTK's own GPU ray caster): `afam replay`'s cameras and transfer function as VTK
// objects, and the statistics they print.
#ifndef BenchRenderLoopScene_h
#define BenchRenderLoopScene_h

#include "afam/base/errors.hpp"
#include "afam/scene/camera.hpp"
#include "afam/scene/trajectory_gen.hpp"
#include "afam/scene/transfer_function.hpp"

#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkNew.h"
#include "vtkPiecewiseFunction.h"
#include "vtkVolumeProperty.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

namespace
{
// What both benchmarks take: the input, the camera path, the window's size, the frames to render,
// a cold start and the CSV file.
// --view K draws every frame from point of view K (a run's playback with a still camera); with
// it, --frames may ask for more frames than the path has. Inputs after the first: a run's later
// steps (BenchVTKRawVolume).
struct PathOptions
{
  std::string File, Trajectory, Csv;
  std::vector<std::string> MoreFiles;
  int Orbit = 0, Size = 512, Frames = 0, View = -1;
  bool Cold = false;
};

// Takes argv[i] (with its value, advancing i) when it is one of PathOptions' arguments; false
// when it is not.
bool ParsePathOption(int argc, char* argv[], int& i, PathOptions& o)
{
  const std::string a = argv[i];
  const bool hasValue = i + 1 < argc;
  if (a == "--trajectory" && hasValue)
    o.Trajectory = argv[++i];
  else if (a == "--orbit" && hasValue)
    o.Orbit = std::atoi(argv[++i]);
  else if (a == "--size" && hasValue)
    o.Size = std::atoi(argv[++i]);
  else if (a == "--frames" && hasValue)
    o.Frames = std::atoi(argv[++i]);
  else if (a == "--csv" && hasValue)
    o.Csv = argv[++i];
  else if (a == "--cold")
    o.Cold = true;
  else if (a == "--view" && hasValue)
    o.View = std::atoi(argv[++i]);
  else if (a[0] != '-' && o.File.empty())
    o.File = a;
  else if (a[0] != '-')
    o.MoreFiles.push_back(a);
  else
    return false;
  return true;
}

// An input, exactly one camera path and a size in [16, 8192].
bool PathOptionsComplete(const PathOptions& o)
{
  return !o.File.empty() && (o.Trajectory.empty() != (o.Orbit < 1)) && o.Size >= 16 &&
    o.Size <= 8192;
}

// The points of view of --trajectory or --orbit, the first --frames of them. Throws afam::Error.
std::vector<afam::Pose> LoadPoses(const PathOptions& o)
{
  std::vector<afam::Pose> poses = o.Trajectory.empty()
    ? afam::orbitTrajectory(o.Orbit, 1.5, 60.0, 0.0, 1.0)
    : afam::loadTrajectory(o.Trajectory);
  if (o.View >= 0)
  {
    if (static_cast<size_t>(o.View) >= poses.size())
    {
      throw afam::InvalidArgument("--view " + std::to_string(o.View) + " outside the path's " +
        std::to_string(poses.size()) + " points of view");
    }
    poses.assign(o.Frames > 0 ? static_cast<size_t>(o.Frames) : poses.size(),
      poses[static_cast<size_t>(o.View)]);
  }
  if (o.Frames > 0 && static_cast<size_t>(o.Frames) < poses.size())
  {
    poses.resize(static_cast<size_t>(o.Frames));
  }
  return poses;
}

// The volume's box from its bounds: centre, half extents and the normalised frame's unit length.
struct VolumeBox
{
  double Centre[3], Half[3], Unit;
};
VolumeBox BoxOf(const double b[6])
{
  VolumeBox box;
  for (int a = 0; a < 3; ++a)
  {
    box.Centre[a] = 0.5 * (b[2 * a] + b[2 * a + 1]);
    box.Half[a] = 0.5 * (b[2 * a + 1] - b[2 * a]);
  }
  box.Unit = std::cbrt(box.Half[0] * box.Half[1] * box.Half[2]);
  return box;
}

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
