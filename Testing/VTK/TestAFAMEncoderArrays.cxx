// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// Which array vtkAFAMEncoder encodes when none (or an empty name, as a ParaView proxy leaves it)
// is chosen: the active point scalars, else the only one-component point array; when none fits,
// the error names the arrays that could be chosen.
// Usage: TestAFAMEncoderArrays
#include "vtkAFAMEncoder.h"

#include "vtkCallbackCommand.h"
#include "vtkCommand.h"
#include "vtkDataObject.h"
#include "vtkExecutive.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkSmartPointer.h"

#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

namespace
{
int failures = 0;

void Check(bool ok, const std::string& what)
{
  std::cout << (ok ? "ok: " : "FAILED: ") << what << "\n";
  failures += ok ? 0 : 1;
}

vtkSmartPointer<vtkFloatArray> Ramp(const char* name, int n, float scale, int components = 1)
{
  auto a = vtkSmartPointer<vtkFloatArray>::New();
  a->SetName(name);
  a->SetNumberOfComponents(components);
  a->SetNumberOfTuples(static_cast<vtkIdType>(n) * n * n);
  for (vtkIdType i = 0; i < a->GetNumberOfValues(); ++i)
  {
    a->SetValue(i, scale * static_cast<float>(i % 97));
  }
  return a;
}

/// Encodes `image`; returns the error messages (empty on success); `encoded` gets the model file
/// (empty when nothing was encoded).
std::vector<std::string> Encode(vtkImageData* image, const char* selected, std::string& encoded)
{
  std::vector<std::string> errors;
  vtkNew<vtkCallbackCommand> watch;
  watch->SetCallback([](vtkObject*, unsigned long, void* clientData, void* callData) {
    static_cast<std::vector<std::string>*>(clientData)->push_back(
      callData ? static_cast<const char*>(callData) : "");
  });
  watch->SetClientData(&errors);
  vtkNew<vtkAFAMEncoder> encoder;
  encoder->AddObserver(vtkCommand::ErrorEvent, watch);
  encoder->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, watch);
  encoder->SetInputData(image);
  encoder->SetLevels(1);
  encoder->SetBlocksPerAxis(1);
  encoder->SetErrorBound(0.05);
  if (selected)
  {
    encoder->SetInputArrayToProcess(0, 0, 0, vtkDataObject::FIELD_ASSOCIATION_POINTS, selected);
  }
  encoder->Update();
  encoded.clear();
  if (encoder->GetModelFileName()[0] != '\0')
  {
    encoded = encoder->GetModelFileName();
  }
  return errors;
}

bool Mentions(const std::vector<std::string>& errors, const std::vector<std::string>& parts)
{
  if (errors.empty())
  {
    return false;
  }
  for (const std::string& p : parts)
  {
    if (errors[0].find(p) == std::string::npos)
    {
      return false;
    }
  }
  return true;
}
}

int main(int, char*[])
{
  const int n = 9;
  std::string encoded;
  {
    // One point array, not marked active: it is the one to encode.
    vtkNew<vtkImageData> image;
    image->SetDimensions(n, n, n);
    image->GetPointData()->AddArray(Ramp("density", n, 1.0f));
    Check(Encode(image, nullptr, encoded).empty() && !encoded.empty(),
      "the only one-component array is encoded without a choice");
    Check(Encode(image, "", encoded).empty() && !encoded.empty(),
      "an empty name (ParaView's unset property) encodes it too");
  }
  {
    // Active scalars among several arrays.
    vtkNew<vtkImageData> image;
    image->SetDimensions(n, n, n);
    image->GetPointData()->AddArray(Ramp("pressure", n, 2.0f));
    image->GetPointData()->SetScalars(Ramp("temperature", n, 3.0f));
    Check(Encode(image, "", encoded).empty() && !encoded.empty(), "the active scalars are encoded");
  }
  {
    // Two candidates, none active: the error lists both.
    vtkNew<vtkImageData> image;
    image->SetDimensions(n, n, n);
    image->GetPointData()->AddArray(Ramp("pressure", n, 2.0f));
    image->GetPointData()->AddArray(Ramp("temperature", n, 3.0f));
    image->GetPointData()->AddArray(Ramp("velocity", n, 1.0f, 3));
    const std::vector<std::string> errors = Encode(image, "", encoded);
    Check(encoded.empty() && Mentions(errors, { "'pressure'", "'temperature'" }) &&
        errors[0].find("velocity") == std::string::npos,
      "no choice among two arrays: " + (errors.empty() ? std::string("no error") : errors[0]));
    const std::vector<std::string> missing = Encode(image, "salinity", encoded);
    Check(encoded.empty() && Mentions(missing, { "'salinity'", "'pressure'", "'temperature'" }),
      "a missing array is named: " + (missing.empty() ? std::string("no error") : missing[0]));
    const std::vector<std::string> vector = Encode(image, "velocity", encoded);
    Check(encoded.empty() && Mentions(vector, { "'velocity' has 3 components", "'pressure'" }),
      "a vector array is refused: " + (vector.empty() ? std::string("no error") : vector[0]));
  }
  std::cout << failures << " failure(s)\n";
  return failures == 0 ? EXIT_SUCCESS : EXIT_FAILURE;
}
