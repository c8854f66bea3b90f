// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
/**
 * @brief   What marks the encoding filter's missing samples besides NaN (private to the module;
 *          vtkAFAMEncoder): a valid-point mask array and a fill value.
 *
 * A valid-point mask is a one-component point array of char, signed char or unsigned char values
 * (VTK's vtkValidPointMask, which vtkProbeFilter and vtkResampleToImage leave): 0 marks a missing
 * sample. A fill value marks the samples equal to it (a land mask's -999). Both are checked here,
 * with errors that name the array or the value; the samples are marked as the encoder reads them
 * (afam::ValidMaskSource, afam::MissingValueSource), never copied whole.
 */
#ifndef vtkAFAMMissingSamples_h
#define vtkAFAMMissingSamples_h

#include "afam/volume/missing_value_source.hpp"
#include "afam/volume/sample_type.hpp"
#include "afam/volume/valid_mask_source.hpp"

#include "vtkDataArray.h"
#include "vtkSmartPointer.h"

#include <cstdint>
#include <memory>
#include <string>

class vtkPointData;

/// A valid-point mask's bytes (nullptr: no mask), one a point, x fastest.
struct vtkAFAMValidMask
{
  const uint8_t* Valid = nullptr;
  std::string Name;
  /// The same bytes where the array keeps them in another layout (structure of arrays).
  vtkSmartPointer<vtkDataArray> Copy;
};

/// The mask array `name` of `pointData` for `points` points: false, with `error` naming the array,
/// when it has the wrong type, components or size. An empty name, or a name no array has, gives
/// no mask (true, mask.Valid null).
bool vtkAFAMFindValidMask(vtkPointData* pointData,
  const char* name,
  vtkIdType points,
  vtkAFAMValidMask& mask,
  std::string& error);

/// "" when `value` can mark missing samples of the array `arrayName` of `type`, else why not,
/// naming the value and the array.
std::string vtkAFAMMissingValueProblem(double value,
  afam::SampleType type,
  const std::string& arrayName);

/// The encoder's source with the missing samples marked: those the mask says are not valid, and
/// with `useValue`, those equal to `value` (checked beforehand: vtkAFAMMissingValueProblem).
class vtkAFAMMarkedSource
{
public:
  vtkAFAMMarkedSource(afam::VolumeSource& values,
    const uint8_t* valid,
    bool useValue,
    double value,
    afam::SampleType type);
  afam::VolumeSource& Source()
  {
    return *this->Top;
  }
  /// A fill value was given and no sample read so far equalled it.
  bool ValueNeverFound() const
  {
    return this->Filled && this->Filled->matches() == 0;
  }

private:
  std::unique_ptr<afam::ValidMaskSource> Masked;
  std::unique_ptr<afam::MissingValueSource> Filled;
  afam::VolumeSource* Top;
};

/// The warning when a fill value never occurred: the encode went on with every sample valid.
std::string vtkAFAMValueNeverFound(double value, const std::string& arrayName);

#endif
