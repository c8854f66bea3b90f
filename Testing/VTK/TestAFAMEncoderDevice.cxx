// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// vtkAFAMEncoder's Device (afam encode --device): CPU, Auto and GPU write the same file; CPU and
// Auto never warn; GPU uses the GPU where one is usable, else warns once and encodes on the CPU;
// LastDevice says which.
// Usage: TestAFAMEncoderDevice
#include "vtkAFAMEncoder.h"

#include "vtkCallbackCommand.h"
#include "vtkCommand.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPointData.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>

namespace
{
int failures = 0;

void Check(bool ok, const std::string& what)
{
  std::cout << (ok ? "ok: " : "FAILED: ") << what << "\n";
  failures += ok ? 0 : 1;
}

std::string Slurp(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

struct Encoded
{
  std::string bytes, device;
  int warnings = 0;
};

/// 48^3 samples of a smooth field with a ripple: blocks of 12, most of them searched.
Encoded Encode(int device)
{
  const int n = 48;
  vtkNew<vtkImageData> image;
  image->SetDimensions(n, n, n);
  vtkNew<vtkFloatArray> values;
  values->SetName("density");
  values->SetNumberOfTuples(static_cast<vtkIdType>(n) * n * n);
  vtkIdType i = 0;
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
        values->SetValue(
          i++, static_cast<float>(std::sin(0.3 * x) * std::cos(0.2 * y) + 0.1 * std::sin(1.7 * z)));
  image->GetPointData()->SetScalars(values);
  Encoded out;
  vtkNew<vtkCallbackCommand> watch;
  watch->SetCallback(
    [](vtkObject*, unsigned long, void* count, void*) { ++*static_cast<int*>(count); });
  watch->SetClientData(&out.warnings);
  vtkNew<vtkAFAMEncoder> encoder;
  encoder->AddObserver(vtkCommand::WarningEvent, watch);
  encoder->SetInputData(image);
  encoder->SetLevels(2);
  encoder->SetBlocksPerAxis(4);
  encoder->SetErrorBound(1e-3);
  encoder->SetDevice(device);
  encoder->Update();
  out.bytes = Slurp(encoder->GetModelFileName());
  out.device = encoder->GetLastDevice();
  return out;
}
}

int main(int, char*[])
{
  const Encoded cpu = Encode(vtkAFAMEncoder::DEVICE_CPU);
  const Encoded automatic = Encode(vtkAFAMEncoder::DEVICE_AUTO);
  const Encoded gpu = Encode(vtkAFAMEncoder::DEVICE_GPU);
  Check(!cpu.bytes.empty() && cpu.device == "cpu" && cpu.warnings == 0,
    "CPU encodes on the CPU, silently (" + std::to_string(cpu.bytes.size()) + " bytes)");
  Check(automatic.bytes == cpu.bytes && automatic.warnings == 0,
    "Auto writes the CPU's file, silently, on " + automatic.device);
  Check(gpu.bytes == cpu.bytes, "GPU writes the CPU's file, on " + gpu.device);
  const bool onGpu = gpu.device.rfind("gpu ", 0) == 0;
  Check(onGpu ? gpu.warnings == 0 : gpu.warnings == 1 && gpu.device == "cpu",
    "GPU: " + std::string(onGpu ? "the GPU, no warning" : "no usable GPU, one warning") + " (" +
      std::to_string(gpu.warnings) + " warnings)");
  Check(automatic.device == gpu.device, "Auto takes the GPU exactly where GPU does");
  std::cout << failures << " failure(s)\n";
  return failures == 0 ? EXIT_SUCCESS : EXIT_FAILURE;
}
