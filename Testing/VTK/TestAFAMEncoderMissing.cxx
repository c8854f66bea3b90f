// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// Missing samples through vtkAFAMEncoder and vtkAFAMReader: an image with NaN holes, one with a
// vtkValidPointMask array (0 = missing) and an int16 one with a fill value (UseMissingValue) are
// encoded with a pointwise bound and read back (DecodeLevel, the finest level): NaN exactly at the
// missing points, every valid point within the bound, and the root's field data says what marked
// them (AFAM_MissingKind, AFAM_MissingValue). Bad input is refused by name: a mask of the wrong
// size or type, a fill value that is NaN or that int16 / uint8 cannot hold, an image with no valid
// sample; a fill value no sample equals is warned about and the encode goes on.
// Usage: TestAFAMEncoderMissing
#include "vtkAFAMEncoder.h"
#include "vtkAFAMReader.h"

#include "vtkCallbackCommand.h"
#include "vtkCharArray.h"
#include "vtkCommand.h"
#include "vtkDataArray.h"
#include "vtkDoubleArray.h"
#include "vtkExecutive.h"
#include "vtkFieldData.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkMultiBlockDataSet.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkShortArray.h"
#include "vtkSmartPointer.h"
#include "vtkStringArray.h"
#include "vtkUnsignedCharArray.h"

#include <cmath>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

namespace
{
int failures = 0;
const int Dims[3] = { 19, 17, 15 }; // awkward sizes, as VTK's own tests use

void Check(bool ok, const std::string& what)
{
  std::cout << (ok ? "ok: " : "FAILED: ") << what << "\n";
  failures += ok ? 0 : 1;
}

vtkIdType Points()
{
  return static_cast<vtkIdType>(Dims[0]) * Dims[1] * Dims[2];
}

/// A smooth field, and the points that are missing: a ball and a corner box (a whole block of
/// the finest level, so that it is stored empty).
double Field(vtkIdType i)
{
  const double x = static_cast<double>(i % Dims[0]),
               y = static_cast<double>((i / Dims[0]) % Dims[1]),
               z = static_cast<double>(i / (Dims[0] * Dims[1]));
  return std::sin(0.3 * x) * std::cos(0.25 * y) + 0.04 * z;
}

bool IsMissing(vtkIdType i)
{
  const int x = static_cast<int>(i % Dims[0]), y = static_cast<int>((i / Dims[0]) % Dims[1]),
            z = static_cast<int>(i / (Dims[0] * Dims[1]));
  const int dx = x - 12, dy = y - 9, dz = z - 8;
  return dx * dx + dy * dy + dz * dz <= 16 || (x < 8 && y < 7 && z < 6);
}

vtkSmartPointer<vtkImageData> Image(vtkDataArray* values)
{
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(Dims[0], Dims[1], Dims[2]);
  image->GetPointData()->SetScalars(values);
  return image;
}

/// The field as float, NaN at the missing points when `holes`, `garbage` there otherwise.
vtkSmartPointer<vtkFloatArray> FloatField(bool holes, float garbage = 0)
{
  auto a = vtkSmartPointer<vtkFloatArray>::New();
  a->SetName("temperature");
  a->SetNumberOfTuples(Points());
  for (vtkIdType i = 0; i < Points(); ++i)
  {
    const bool gone = IsMissing(i);
    a->SetValue(i,
      gone && holes ? std::numeric_limits<float>::quiet_NaN()
        : gone      ? garbage
                    : static_cast<float>(Field(i)));
  }
  return a;
}

/// vtkValidPointMask as vtkProbeFilter leaves it: 1 valid, 0 missing.
vtkSmartPointer<vtkCharArray> Mask(vtkIdType count)
{
  auto m = vtkSmartPointer<vtkCharArray>::New();
  m->SetName("vtkValidPointMask");
  m->SetNumberOfTuples(count);
  for (vtkIdType i = 0; i < count; ++i)
  {
    m->SetValue(i, IsMissing(i) ? 0 : 1);
  }
  return m;
}

/// What an encode (and the read-back of its finest level) gave.
struct Encoded
{
  std::vector<std::string> errors, warnings;
  bool file = false;
  vtkSmartPointer<vtkDataArray> decoded; ///< the finest level as the reader decodes it
  std::string missingKind;
  double missingValue = 0, bound = 0;
};

void Watch(vtkObject* object, unsigned long event, std::vector<std::string>& into)
{
  vtkNew<vtkCallbackCommand> watch;
  watch->SetCallback(
    [](vtkObject*, unsigned long, void* clientData, void* callData)
    {
      static_cast<std::vector<std::string>*>(clientData)
        ->push_back(callData ? static_cast<const char*>(callData) : "");
    });
  watch->SetClientData(&into);
  object->AddObserver(event, watch);
}

void ReadBack(const char* path, Encoded& result)
{
  vtkNew<vtkAFAMReader> reader;
  reader->SetFileName(path);
  reader->SetDecodeLevel(1); // the finest of the two levels: the image's own grid
  reader->Update();
  auto* image = vtkImageData::SafeDownCast(reader->GetOutputDataObject(1));
  result.decoded = image ? image->GetPointData()->GetScalars() : nullptr;
  vtkFieldData* fd = reader->GetOutput()->GetFieldData();
  auto* kind = vtkStringArray::SafeDownCast(fd->GetAbstractArray("AFAM_MissingKind"));
  vtkDataArray* value = fd->GetArray("AFAM_MissingValue");
  result.missingKind = kind ? kind->GetValue(0) : "(no AFAM_MissingKind)";
  result.missingValue = value ? value->GetTuple1(0) : -1;
}

Encoded Encode(vtkImageData* image, const std::function<void(vtkAFAMEncoder*)>& configure = {})
{
  Encoded result;
  vtkNew<vtkAFAMEncoder> encoder;
  Watch(encoder, vtkCommand::ErrorEvent, result.errors);
  Watch(encoder->GetExecutive(), vtkCommand::ErrorEvent, result.errors);
  Watch(encoder, vtkCommand::WarningEvent, result.warnings);
  encoder->SetInputData(image);
  encoder->SetLevels(2);
  encoder->SetBlocksPerAxis(2);
  encoder->SetBoundKind(vtkAFAMEncoder::BOUND_MAX_ERROR);
  encoder->SetErrorBound(0.01);
  encoder->SetNumberOfThreads(2);
  if (configure)
  {
    configure(encoder);
  }
  encoder->Update();
  result.file = encoder->GetModelFileName()[0] != '\0';
  result.bound = encoder->GetLastBound();
  if (result.file)
  {
    ReadBack(encoder->GetModelFileName(), result);
  }
  return result;
}

/// NaN exactly at the missing points, every other point within the bound of `original`.
void CheckDecoded(const Encoded& e, vtkDataArray* original, const std::string& what)
{
  if (!e.file || !e.decoded || e.decoded->GetNumberOfTuples() != Points())
  {
    Check(false,
      what + ": encoded and read back (errors: " +
        (e.errors.empty() ? std::string("none") : e.errors[0]) + ")");
    return;
  }
  vtkIdType wrongMask = 0, missing = 0, outside = 0;
  double worst = 0;
  for (vtkIdType i = 0; i < Points(); ++i)
  {
    const double d = e.decoded->GetTuple1(i);
    missing += IsMissing(i) ? 1 : 0;
    wrongMask += std::isnan(d) != IsMissing(i) ? 1 : 0;
    if (!IsMissing(i) && !std::isnan(d))
    {
      const double error = std::fabs(d - original->GetTuple1(i));
      worst = std::max(worst, error);
      outside += error > e.bound * (1 + 1e-5) ? 1 : 0;
    }
  }
  Check(wrongMask == 0 && missing > 0,
    what + ": NaN exactly at the " + std::to_string(missing) + " missing points (" +
      std::to_string(wrongMask) + " wrong)");
  Check(outside == 0 && e.bound > 0,
    what + ": valid points within the bound " + std::to_string(e.bound) + " (worst " +
      std::to_string(worst) + ")");
}

bool Says(const std::vector<std::string>& messages, const std::vector<std::string>& parts)
{
  for (const std::string& m : messages)
  {
    bool all = true;
    for (const std::string& p : parts)
    {
      all = all && m.find(p) != std::string::npos;
    }
    if (all)
    {
      return true;
    }
  }
  return false;
}

std::string First(const std::vector<std::string>& messages)
{
  return messages.empty() ? std::string("none") : messages[0];
}

void MarkedMissing()
{
  vtkSmartPointer<vtkFloatArray> truth = FloatField(false);
  const Encoded nan = Encode(Image(FloatField(true)));
  CheckDecoded(nan, truth, "NaN holes");
  Check(nan.missingKind == "nan", "NaN holes: AFAM_MissingKind " + nan.missingKind);

  vtkSmartPointer<vtkImageData> probed = Image(FloatField(false, 1e3f)); // a probe's leftovers
  probed->GetPointData()->AddArray(Mask(Points()));
  const Encoded masked = Encode(probed);
  CheckDecoded(masked, truth, "vtkValidPointMask");
  Check(masked.missingKind == "nan", "vtkValidPointMask: AFAM_MissingKind " + masked.missingKind);
  const Encoded unmasked =
    Encode(probed, [](vtkAFAMEncoder* e) { e->SetValidPointMaskArrayName(""); });
  Check(unmasked.file && unmasked.missingKind == "none",
    "no mask name: every point valid (AFAM_MissingKind " + unmasked.missingKind + ")");

  auto counts = vtkSmartPointer<vtkShortArray>::New(); // int16 with a fill value
  counts->SetName("depth");
  counts->SetNumberOfTuples(Points());
  for (vtkIdType i = 0; i < Points(); ++i)
  {
    counts->SetValue(i, static_cast<short>(IsMissing(i) ? -999 : std::lround(1000 * Field(i))));
  }
  const Encoded filled = Encode(Image(counts),
    [](vtkAFAMEncoder* e)
    {
      e->UseMissingValueOn();
      e->SetMissingValue(-999);
    });
  CheckDecoded(filled, counts, "int16 with MissingValue -999");
  Check(filled.missingKind == "value" && filled.missingValue == -999,
    "MissingValue: AFAM_MissingKind " + filled.missingKind + " AFAM_MissingValue " +
      std::to_string(filled.missingValue));
}

void WrongMasks()
{
  vtkSmartPointer<vtkImageData> image = Image(FloatField(false));
  image->GetPointData()->AddArray(Mask(Points() - Dims[0]));
  const Encoded shortMask = Encode(image);
  Check(!shortMask.file &&
      Says(shortMask.errors, { "'vtkValidPointMask'", std::to_string(Points() - Dims[0]) }),
    "a mask of the wrong size is refused by name: " + First(shortMask.errors));

  vtkSmartPointer<vtkImageData> floats = Image(FloatField(false));
  vtkSmartPointer<vtkFloatArray> notBytes = FloatField(false);
  notBytes->SetName("valid");
  floats->GetPointData()->AddArray(notBytes);
  const Encoded floatMask =
    Encode(floats, [](vtkAFAMEncoder* e) { e->SetValidPointMaskArrayName("valid"); });
  Check(!floatMask.file && Says(floatMask.errors, { "'valid'", "float" }),
    "a float mask is refused by name: " + First(floatMask.errors));
}

void WrongValues()
{
  const auto value = [](double v)
  {
    return [v](vtkAFAMEncoder* e)
    {
      e->UseMissingValueOn();
      e->SetMissingValue(v);
    };
  };
  const Encoded nan =
    Encode(Image(FloatField(false)), value(std::numeric_limits<double>::quiet_NaN()));
  Check(!nan.file && Says(nan.errors, { "MissingValue", "NaN" }),
    "a NaN MissingValue is refused: " + First(nan.errors));

  auto shorts = vtkSmartPointer<vtkShortArray>::New();
  shorts->SetName("depth");
  shorts->SetNumberOfTuples(Points());
  shorts->Fill(3);
  const Encoded wide = Encode(Image(shorts), value(40000));
  Check(!wide.file && Says(wide.errors, { "MissingValue 40000", "'depth'", "int16" }),
    "a MissingValue int16 cannot hold is refused: " + First(wide.errors));

  auto bytes = vtkSmartPointer<vtkUnsignedCharArray>::New();
  bytes->SetName("label");
  bytes->SetNumberOfTuples(Points());
  for (vtkIdType i = 0; i < Points(); ++i)
  {
    bytes->SetValue(i, static_cast<unsigned char>(i % 97));
  }
  const Encoded fraction = Encode(Image(bytes), value(7.5));
  Check(!fraction.file && Says(fraction.errors, { "7.5", "not an integer" }),
    "a fractional MissingValue of uint8 is refused: " + First(fraction.errors));
  const Encoded absent = Encode(Image(bytes), value(200));
  Check(absent.file && absent.errors.empty() && absent.missingKind == "none" &&
      Says(absent.warnings, { "'label'", "MissingValue 200" }),
    "a MissingValue no sample equals: a warning, and the encode goes on: " +
      First(absent.warnings));
}

void NoValidSample()
{
  auto none = vtkSmartPointer<vtkFloatArray>::New();
  none->SetName("temperature");
  none->SetNumberOfTuples(Points());
  none->Fill(std::numeric_limits<float>::quiet_NaN());
  const Encoded allNan = Encode(Image(none));
  Check(!allNan.file && Says(allNan.errors, { "no valid sample" }),
    "an image of NaN only is refused: " + First(allNan.errors));

  vtkSmartPointer<vtkImageData> image = Image(FloatField(false));
  auto zeros = vtkSmartPointer<vtkCharArray>::New();
  zeros->SetName("vtkValidPointMask");
  zeros->SetNumberOfTuples(Points());
  zeros->Fill(0);
  image->GetPointData()->AddArray(zeros);
  const Encoded allMasked = Encode(image);
  Check(!allMasked.file && Says(allMasked.errors, { "no valid sample" }),
    "an image whose mask is 0 everywhere is refused: " + First(allMasked.errors));
}
}

int main(int, char*[])
{
  MarkedMissing();
  WrongMasks();
  WrongValues();
  NoValidSample();
  std::cout << failures << " failure(s)\n";
  return failures == 0 ? EXIT_SUCCESS : EXIT_FAILURE;
}
