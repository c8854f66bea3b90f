// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// vtkAFAMVolumeMapper keeps its renderer (RAM cache, GPU pool) while the volume property changes:
// colour, opacity, shading, sample-distance and blend-mode edits read nothing from the file, and
// only a change of resources (the cache budget) builds a new one. Unusable settings (an opacity
// or colour function without points, a colour with NaN, an opacity unit distance of 0 or below)
// give one warning naming the setting and the value kept, and the frame is drawn with the last
// usable settings: the same picture as before the bad edit, never a blank one. Odd but usable
// ones (opacity zero everywhere, every point at one value) are drawn as VTK maps them.
// Usage: TestAFAMFrameSettings
#include "AFAMTestScene.h"
#include "vtkAFAMVolumeMapper.h"

#include "vtkRenderWindowInteractor.h"
#include "vtkRenderer.h"

#include <cmath>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <limits>
#include <string>

namespace
{
int failures = 0;

void Check(bool ok, const std::string& what)
{
  std::cout << (ok ? "ok: " : "FAILED: ") << what << "\n";
  failures += ok ? 0 : 1;
}

/// Pixels that differ from the background (26, 26, 38) by more than 8 in some channel.
long Foreground(const std::vector<unsigned char>& rgb)
{
  long n = 0;
  for (size_t i = 0; i + 2 < rgb.size(); i += 3)
  {
    n +=
      (std::abs(rgb[i] - 26) > 8 || std::abs(rgb[i + 1] - 26) > 8 || std::abs(rgb[i + 2] - 38) > 8)
      ? 1
      : 0;
  }
  return n;
}

bool Contains(const std::string& text, const std::string& part)
{
  return text.find(part) != std::string::npos;
}
}

int main(int, char*[])
{
  afam_vtk_test::Scene scene;
  if (!scene.Build())
  {
    return EXIT_FAILURE;
  }
  vtkAFAMVolumeMapper* mapper = scene.Mapper;
  vtkVolumeProperty* property = scene.Property;
  vtkRenderWindow* window = scene.Window;
  std::vector<std::string> warnings;
  auto watch = afam_vtk_test::CollectWarnings(mapper, warnings);

  window->Render();
  const vtkTypeInt64 visible = mapper->GetLastVisibleBlocks();
  Check(mapper->GetLastCacheMisses() > 0 && visible > 0,
    "the first frame reads " + std::to_string(mapper->GetLastCacheMisses()) + " models, " +
      std::to_string(visible) + " visible");

  // Edits that keep every block's visibility: nothing is read, nothing is rebuilt.
  vtkColorTransferFunction* color = property->GetRGBTransferFunction(0);
  vtkPiecewiseFunction* opacity = property->GetScalarOpacity(0);
  const std::vector<std::pair<std::string, std::function<void()>>> edits = {
    { "colour point", [&] { color->AddRGBPoint(0.5, 0.2, 0.9, 0.3); } },
    { "opacity point", [&] { opacity->AddPoint(0.8, 0.3); } },
    { "shading on", [&] { property->ShadeOn(); } },
    { "sample distance", [&] { mapper->SetSampleDistance(0.013); } },
    { "unit distance", [&] { property->SetScalarOpacityUnitDistance(0.07); } },
    { "maximum intensity and back",
      [&]
      {
        mapper->SetBlendModeToMaximumIntensity();
        window->Render();
        mapper->SetBlendModeToComposite();
      } },
  };
  for (const auto& edit : edits)
  {
    edit.second();
    window->Render();
    Check(mapper->GetLastCacheMisses() == 0 && mapper->GetLastBytesRead() == 0 &&
        mapper->GetLastCacheHits() == visible && mapper->GetNumberOfRendererBuilds() == 1,
      edit.first + ": " + std::to_string(mapper->GetLastCacheMisses()) + " misses, " +
        std::to_string(mapper->GetLastCacheHits()) + " hits, " +
        std::to_string(mapper->GetNumberOfRendererBuilds()) + " renderer builds");
  }
  Check(warnings.empty(), "no warning for usable edits (" + std::to_string(warnings.size()) + ")");
  mapper->SetSampleDistance(0); // from here on, the finest sample spacing
  window->Render();
  const std::vector<unsigned char> good = afam_vtk_test::ReadPixels(window);
  const long goodForeground = Foreground(good);

  // Unusable settings: one warning each, the last usable settings drawn.
  struct Bad
  {
    std::string name;
    std::function<void()> apply, undo;
    std::vector<std::string> expected;
  };
  vtkNew<vtkPiecewiseFunction> saved;
  saved->DeepCopy(opacity);
  vtkNew<vtkColorTransferFunction> savedColor;
  savedColor->DeepCopy(color);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Bad> bad = {
    { "opacity without points",
      [&] { opacity->RemoveAllPoints(); },
      [&] { opacity->DeepCopy(saved); },
      { "opacity transfer function has no points", "keeping the last transfer function" } },
    { "colour without points",
      [&] { color->RemoveAllPoints(); },
      [&] { color->DeepCopy(savedColor); },
      { "colour transfer function has no points", "keeping the last transfer function" } },
    { "colour with NaN",
      [&] { color->AddRGBPoint(0.7, nan, 0.5, 0.5); },
      [&] { color->RemovePoint(0.7); },
      { "is not finite", "keeping the last transfer function" } },
    { "unit distance 0",
      [&] { property->SetScalarOpacityUnitDistance(0.0); },
      [&] { property->SetScalarOpacityUnitDistance(0.07); },
      { "opacity unit distance 0 is not", "keeping the last transfer function" } },
    { "unit distance -1",
      [&] { property->SetScalarOpacityUnitDistance(-1.0); },
      [&] { property->SetScalarOpacityUnitDistance(0.07); },
      { "opacity unit distance -", "keeping the last transfer function" } },
  };
  for (const Bad& b : bad)
  {
    warnings.clear();
    b.apply();
    window->Render();
    window->Render(); // the same bad settings again: no second warning
    const std::string all = warnings.empty() ? "" : warnings[0];
    bool named = warnings.size() == 1;
    for (const std::string& part : b.expected)
    {
      named = named && Contains(all, part);
    }
    Check(named, b.name + ": " + std::to_string(warnings.size()) + " warning(s): " + all);
    const std::vector<unsigned char> drawn = afam_vtk_test::ReadPixels(window);
    Check(drawn == good,
      b.name + ": the last usable settings drawn (" + std::to_string(Foreground(drawn)) +
        " foreground pixels, " + std::to_string(goodForeground) + " before)");
    Check(mapper->GetLastCacheMisses() == 0 && mapper->GetNumberOfRendererBuilds() == 1,
      b.name + ": cache kept");
    b.undo();
    window->Render();
    Check(std::string(mapper->GetLastSettingWarning()).empty(),
      b.name + " undone: the warning is gone");
  }

  // Transfer functions ParaView lets a user make: drawn as VTK maps them, never a crash, no
  // warning. Opacity zero everywhere: nothing; every point at one value (a range of zero width):
  // the values below take the first point's colour and opacity and those above the last's.
  struct Odd
  {
    std::string name;
    std::function<void()> apply;
    std::function<bool(long foreground)> expected;
  };
  const std::vector<Odd> odd = {
    { "opacity zero everywhere",
      [&]
      {
        opacity->RemoveAllPoints();
        opacity->AddPoint(0.0, 0.0);
        opacity->AddPoint(1.0, 0.0);
      },
      [&](long fg) { return fg == 0; } },
    { "a range of zero width",
      [&]
      {
        color->RemoveAllPoints();
        color->AddRGBPoint(0.4, 0.9, 0.6, 0.2);
        opacity->RemoveAllPoints();
        opacity->AddPoint(0.4, 0.5);
      },
      [&](long fg) { return fg > 0; } },
  };
  for (const Odd& o : odd)
  {
    warnings.clear();
    o.apply();
    window->Render();
    const long fg = Foreground(afam_vtk_test::ReadPixels(window));
    Check(o.expected(fg), o.name + ": " + std::to_string(fg) + " foreground pixels");
    Check(warnings.empty(),
      o.name + ": no warning (" + (warnings.empty() ? std::string() : warnings[0]) + ")");
    Check(afam_vtk_test::GpuMatchesCpu(window, mapper, "FrameSettings, " + o.name),
      o.name + ": GPU frame equals the CPU frame");
    color->DeepCopy(savedColor);
    opacity->DeepCopy(saved);
  }
  window->Render();
  Check(afam_vtk_test::ReadPixels(window) == good, "the usable settings again: the same image");

  // A resource change is what builds a new renderer (and cache): the counters can tell.
  mapper->SetCacheBudgetMB(64);
  window->Render();
  Check(mapper->GetNumberOfRendererBuilds() == 2 && mapper->GetLastCacheMisses() == visible,
    "a new cache budget builds a new renderer: " +
      std::to_string(mapper->GetNumberOfRendererBuilds()) + " builds, " +
      std::to_string(mapper->GetLastCacheMisses()) + " misses");
  Check(afam_vtk_test::GpuMatchesCpu(window, mapper, "FrameSettings, after the edits"),
    "GPU frame equals the CPU frame");
  std::cout << failures << " failure(s)\n";
  return failures == 0 ? EXIT_SUCCESS : EXIT_FAILURE;
}
