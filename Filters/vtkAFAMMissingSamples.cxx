// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMMissingSamples.h"

#include "vtkPointData.h"
#include "vtkUnsignedCharArray.h"

#include <sstream>

namespace
{
bool IsByteType(int type)
{
  return type == VTK_CHAR || type == VTK_SIGNED_CHAR || type == VTK_UNSIGNED_CHAR;
}
}

bool vtkAFAMFindValidMask(vtkPointData* pointData,
  const char* name,
  vtkIdType points,
  vtkAFAMValidMask& mask,
  std::string& error)
{
  mask = vtkAFAMValidMask();
  vtkAbstractArray* found = name && *name ? pointData->GetAbstractArray(name) : nullptr;
  if (!found)
  {
    return true;
  }
  std::ostringstream why;
  why << "valid-point mask '" << name << "' ";
  vtkDataArray* array = vtkDataArray::SafeDownCast(found);
  if (!array || !IsByteType(array->GetDataType()) || array->GetNumberOfComponents() != 1)
  {
    why << "holds " << found->GetNumberOfComponents() << "-component "
        << found->GetDataTypeAsString() << " values (" << found->GetClassName()
        << "); a mask is one char or unsigned char a point, 0 where the sample is missing";
    error = why.str();
    return false;
  }
  if (array->GetNumberOfTuples() != points)
  {
    why << "has " << array->GetNumberOfTuples() << " values for " << points << " points";
    error = why.str();
    return false;
  }
  if (!array->HasStandardMemoryLayout())
  {
    mask.Copy = vtkSmartPointer<vtkUnsignedCharArray>::New();
    mask.Copy->DeepCopy(array);
  }
  mask.Valid =
    static_cast<const uint8_t*>((mask.Copy ? mask.Copy.Get() : array)->GetVoidPointer(0));
  mask.Name = name;
  return true;
}

std::string vtkAFAMMissingValueProblem(double value,
  afam::SampleType type,
  const std::string& arrayName)
{
  const std::string why = afam::missingValueProblem(value, type);
  if (why.empty())
  {
    return why;
  }
  std::ostringstream msg;
  msg << "MissingValue " << value << " cannot mark missing samples of '" << arrayName << "': it "
      << why;
  return msg.str();
}

std::string vtkAFAMValueNeverFound(double value, const std::string& arrayName)
{
  std::ostringstream msg;
  msg << "no sample of '" << arrayName << "' equals the MissingValue " << value
      << "; every sample was encoded as valid";
  return msg.str();
}

vtkAFAMMarkedSource::vtkAFAMMarkedSource(afam::VolumeSource& values,
  const uint8_t* valid,
  bool useValue,
  double value,
  afam::SampleType type)
  : Top(&values)
{
  if (valid)
  {
    this->Masked = std::make_unique<afam::ValidMaskSource>(*this->Top, valid);
    this->Top = this->Masked.get();
  }
  if (useValue)
  {
    this->Filled = std::make_unique<afam::MissingValueSource>(*this->Top, value, type);
    this->Top = this->Filled.get();
  }
}
