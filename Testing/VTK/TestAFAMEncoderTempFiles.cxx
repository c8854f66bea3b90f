// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// vtkAFAMEncoder's temporary model files: the first encode of a process removes those that a
// process no longer running left behind (a killed pvserver never destroys its filters), and keeps
// those of live processes and files it did not name; its own file goes with the filter.
// Usage: TestAFAMEncoderTempFiles (uses a scratch TMPDIR of its own)
#include "vtkAFAMEncoder.h"

#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPointData.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace
{
int failures = 0;

void Check(bool ok, const std::string& what)
{
  std::cout << (ok ? "ok: " : "FAILED: ") << what << "\n";
  failures += ok ? 0 : 1;
}

fs::path Touch(const fs::path& dir, const std::string& name)
{
  std::ofstream(dir / name) << "left behind";
  return dir / name;
}

/// The id of a process that has exited (a child, reaped).
pid_t DeadPid()
{
  const pid_t child = ::fork();
  if (child == 0)
  {
    ::_exit(0);
  }
  ::waitpid(child, nullptr, 0);
  return child;
}
}

int main()
{
  const fs::path dir = fs::temp_directory_path() / ("afam-tempfiles-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  ::setenv("TMPDIR", dir.c_str(), 1);

  const fs::path orphan = Touch(dir, "afam-encoder-" + std::to_string(DeadPid()) + "-3.afam");
  const fs::path live = Touch(dir, "afam-encoder-" + std::to_string(::getppid()) + "-0.afam");
  const fs::path other = Touch(dir, "afam-encoder-notes.afam");

  vtkNew<vtkImageData> image;
  image->SetDimensions(9, 9, 9);
  vtkNew<vtkFloatArray> values;
  values->SetName("ramp");
  values->SetNumberOfTuples(9 * 9 * 9);
  for (vtkIdType i = 0; i < values->GetNumberOfTuples(); ++i)
  {
    values->SetValue(i, static_cast<float>(i % 9) * 0.5f);
  }
  image->GetPointData()->SetScalars(values);
  {
    vtkNew<vtkAFAMEncoder> encoder;
    encoder->SetInputData(image);
    encoder->SetLevels(1);
    encoder->SetBlocksPerAxis(1);
    encoder->Update();
    const std::string own = encoder->GetModelFileName();
    Check(!own.empty() && fs::path(own).parent_path() == dir && fs::exists(own),
      "the encoder's model file is in TMPDIR: " + own);
    Check(!fs::exists(orphan), "the file of a process that exited is removed: " + orphan.string());
    Check(fs::exists(live), "the file of a live process stays: " + live.string());
    Check(fs::exists(other), "a file of another name stays: " + other.string());
  }
  int left = 0;
  for (const auto& entry : fs::directory_iterator(dir))
  {
    left +=
      entry.path().filename().string().rfind("afam-encoder-" + std::to_string(::getpid()), 0) == 0;
  }
  Check(left == 0, "the encoder's own file goes with the filter");
  fs::remove_all(dir);
  std::cout << (failures ? "TestAFAMEncoderTempFiles FAILED\n"
                         : "TestAFAMEncoderTempFiles passed\n");
  return failures ? EXIT_FAILURE : EXIT_SUCCESS;
}
