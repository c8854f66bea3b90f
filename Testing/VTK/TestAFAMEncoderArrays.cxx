// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// Which array vtkAFAMEncoder encodes when none (or an empty name, as a ParaView proxy leaves it)
// is chosen: the active point scalars, else the only one-component point array; when none fits,
// the error names the arrays that could be chosen. Arrays are encoded in their own type (the same
// file for the same values and sample size, whatever the layout); a type the encoder cannot take
// (bits, strings, several components) is refused with the array and its type named.
// Usage: TestAFAMEncoderArrays
#include "vtkAFAMEncoder.h"

#include "vtkBitArray.h"
#include "vtkCallbackCommand.h"
#include "vtkCommand.h"
#include "vtkDataObject.h"
#include "vtkExecutive.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkSOADataArrayTemplate.h"
#include "vtkSignedCharArray.h"
#include "vtkSmartPointer.h"
#include "vtkStringArray.h"
#include "vtkUnsignedCharArray.h"

#include <cstdlib>
#include <fstream>
#include <iostream>
#include <iterator>
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

/// A one-component array of `name` holding i % 97 (values every 1-byte type holds).
template<class Array>
vtkSmartPointer<Array> ByteRamp(const char* name, int n)
{
  auto a = vtkSmartPointer<Array>::New();
  a->SetName(name);
  a->SetNumberOfComponents(1);
  a->SetNumberOfTuples(static_cast<vtkIdType>(n) * n * n);
  for (vtkIdType i = 0; i < a->GetNumberOfTuples(); ++i)
  {
    a->SetTypedComponent(i, 0, static_cast<typename Array::ValueType>(i % 97));
  }
  return a;
}

std::string Slurp(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// Encodes `image`; returns the error messages (empty on success); `encoded` gets the model file
/// (empty when nothing was encoded), `bytes` (when given) its contents before the filter, and the
/// file with it, goes away.
std::vector<std::string> Encode(vtkImageData* image,
  const char* selected,
  std::string& encoded,
  std::string* bytes = nullptr)
{
  std::vector<std::string> errors;
  vtkNew<vtkCallbackCommand> watch;
  watch->SetCallback(
    [](vtkObject*, unsigned long, void* clientData, void* callData)
    {
      static_cast<std::vector<std::string>*>(clientData)
        ->push_back(callData ? static_cast<const char*>(callData) : "");
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
  if (bytes)
  {
    *bytes = encoded.empty() ? std::string() : Slurp(encoded);
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
  {
    // Arrays in their own type: uint8, int8 and a uint8 array of another layout (structure of
    // arrays) with the same values give the same file.
    std::vector<std::string> files;
    for (vtkSmartPointer<vtkDataArray> values :
      { vtkSmartPointer<vtkDataArray>(ByteRamp<vtkUnsignedCharArray>("density", n)),
        vtkSmartPointer<vtkDataArray>(ByteRamp<vtkSignedCharArray>("density", n)),
        vtkSmartPointer<vtkDataArray>(
          ByteRamp<vtkSOADataArrayTemplate<unsigned char>>("density", n)) })
    {
      vtkNew<vtkImageData> image;
      image->SetDimensions(n, n, n);
      image->GetPointData()->SetScalars(values);
      files.emplace_back();
      const std::vector<std::string> errors = Encode(image, "density", encoded, &files.back());
      Check(errors.empty() && !files.back().empty(),
        std::string("an array of ") + values->GetDataTypeAsString() + " values" +
          (values->HasStandardMemoryLayout() ? "" : " in another layout") + " is encoded");
    }
    Check(!files[0].empty() && files[0] == files[1] && files[0] == files[2],
      "uint8, int8 and a structure-of-arrays uint8 of the same values give the same file");
  }
  {
    // Types the encoder cannot take: bits, strings, two components (a complex spectrum).
    vtkNew<vtkImageData> image;
    image->SetDimensions(n, n, n);
    vtkNew<vtkBitArray> bits;
    bits->SetName("flags");
    bits->SetNumberOfTuples(static_cast<vtkIdType>(n) * n * n);
    vtkNew<vtkStringArray> labels;
    labels->SetName("labels");
    labels->SetNumberOfTuples(static_cast<vtkIdType>(n) * n * n);
    image->GetPointData()->AddArray(bits);
    image->GetPointData()->AddArray(labels);
    image->GetPointData()->AddArray(Ramp("spectrum", n, 1.0f, 2));
    const std::vector<std::string> bitErrors = Encode(image, "flags", encoded);
    Check(encoded.empty() && Mentions(bitErrors, { "'flags'", "bit", "vtkBitArray", "uint8" }),
      "a bit array is refused: " + (bitErrors.empty() ? std::string("no error") : bitErrors[0]));
    image->GetPointData()->SetActiveScalars("flags");
    const std::vector<std::string> activeBits = Encode(image, nullptr, encoded);
    Check(encoded.empty() && Mentions(activeBits, { "'flags'", "vtkBitArray" }),
      "active bit scalars are refused: " +
        (activeBits.empty() ? std::string("no error") : activeBits[0]));
    const std::vector<std::string> stringErrors = Encode(image, "labels", encoded);
    Check(encoded.empty() &&
        Mentions(stringErrors, { "'labels'", "string", "vtkStringArray", "take: none" }),
      "a string array is refused: " +
        (stringErrors.empty() ? std::string("no error") : stringErrors[0]));
    const std::vector<std::string> complexErrors = Encode(image, "spectrum", encoded);
    Check(encoded.empty() && Mentions(complexErrors, { "'spectrum' has 2 components", "float" }),
      "a two-component array is refused: " +
        (complexErrors.empty() ? std::string("no error") : complexErrors[0]));
  }
  std::cout << failures << " failure(s)\n";
  return failures == 0 ? EXIT_SUCCESS : EXIT_FAILURE;
}
