// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMReader.h"

#include "vtkAFAMModelTree.h"

#include "afam/render/level_decode.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/encode/encoder.hpp"
#include "afam/base/errors.hpp"

#include "vtkDataObject.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkMultiBlockDataSet.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkStreamingDemandDrivenPipeline.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkAFAMReader);

namespace
{
/// Origin and spacing of a level's decoded grid: it spans the volume's bounds.
void LevelGeometry(const afam::VolumeHeader& h,
  const afam::Index3& dims,
  double origin[3],
  double spacing[3])
{
  for (int a = 0; a < 3; ++a)
  {
    origin[a] = h.origin[a];
    const double extent = h.spacing[a] * static_cast<double>(std::max<int64_t>(0, h.dims[a] - 1));
    spacing[a] = dims[a] > 1 ? extent / static_cast<double>(dims[a] - 1) : h.spacing[a];
  }
}
}

vtkAFAMReader::vtkAFAMReader()
{
  this->SetNumberOfInputPorts(0);
  this->SetNumberOfOutputPorts(2);
}

int vtkAFAMReader::FillOutputPortInformation(int port, vtkInformation* info)
{
  info->Set(vtkDataObject::DATA_TYPE_NAME(), port == 0 ? "vtkMultiBlockDataSet" : "vtkImageData");
  return 1;
}

vtkAFAMReader::~vtkAFAMReader()
{
  this->SetFileName(nullptr);
}

int vtkAFAMReader::CanReadFile(const char* filename)
{
  if (!filename || !*filename)
  {
    return 0;
  }
  // Claimed without parsing the rest: a damaged, truncated, newer or foreign file that starts
  // with the magic or is named .afam is the reader's to explain (one error that says what is
  // wrong with it), not ParaView's "No reader found" or its reader-choice dialog.
  if (afam::startsWithAfamMagic(filename))
  {
    return 1;
  }
  const std::string name(filename);
  const std::string ext = ".afam";
  return name.size() >= ext.size() && name.compare(name.size() - ext.size(), ext.size(), ext) == 0
    ? 1
    : 0;
}

void vtkAFAMReader::ReportOnce(const std::string& message)
{
  // RequestInformation and RequestData of every update meet the same bad file: the user is told
  // once, and the pipeline gets an empty output rather than a failure (which VTK's executive
  // would report again, in words about requests).
  if (message != this->LastError)
  {
    this->LastError = message;
    vtkErrorMacro(<< message);
  }
}

namespace
{
// A run's time steps and range on an output's information (nothing for one step).
void SetTimeSteps(vtkInformation* info, const std::vector<double>& times)
{
  if (times.size() < 2)
  {
    info->Remove(vtkStreamingDemandDrivenPipeline::TIME_STEPS());
    info->Remove(vtkStreamingDemandDrivenPipeline::TIME_RANGE());
    return;
  }
  info->Set(
    vtkStreamingDemandDrivenPipeline::TIME_STEPS(), times.data(), static_cast<int>(times.size()));
  const double range[2] = { times.front(), times.back() };
  info->Set(vtkStreamingDemandDrivenPipeline::TIME_RANGE(), range, 2);
}
}

int vtkAFAMReader::RequestInformation(vtkInformation*,
  vtkInformationVector**,
  vtkInformationVector* outV)
{
  if (!this->FileName || !*this->FileName)
  {
    vtkErrorMacro(<< "No file name set.");
    return 0;
  }
  // Pieces are groups of coarsest blocks (see vtkAFAMModelTree::Build).
  outV->GetInformationObject(0)->Set(CAN_HANDLE_PIECE_REQUEST(), 1);
  try
  {
    const std::vector<double> times = afam::AfamFile::open(this->FileName)->stepTimes();
    SetTimeSteps(outV->GetInformationObject(0), times);
    SetTimeSteps(outV->GetInformationObject(1), times);
    this->LastError.clear();
  }
  catch (const std::exception& e)
  {
    this->ReportOnce(e.what()); // at open time: File > Open, OpenDataFile
  }
  // Port 1: the decoded level's grid, or an empty extent when no level is asked for.
  vtkInformation* imageInfo = outV->GetInformationObject(1);
  int whole[6] = { 0, -1, 0, -1, 0, -1 };
  if (this->DecodeLevel >= 0)
  {
    try
    {
      auto file = afam::AfamFile::open(this->FileName);
      const afam::LevelGrid grid = afam::levelGrid(file->partition(), this->DecodeLevel);
      double origin[3], spacing[3];
      LevelGeometry(file->header(), grid.dims, origin, spacing);
      for (int a = 0; a < 3; ++a)
      {
        whole[2 * a + 1] = static_cast<int>(grid.dims[a] - 1);
      }
      imageInfo->Set(vtkDataObject::ORIGIN(), origin, 3);
      imageInfo->Set(vtkDataObject::SPACING(), spacing, 3);
      vtkDataObject::SetPointDataActiveScalarInfo(imageInfo, VTK_FLOAT, 1);
    }
    catch (const std::exception&)
    {
      // Reported by RequestData, which then leaves both outputs empty.
    }
  }
  imageInfo->Set(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), whole, 6);
  imageInfo->Set(CAN_PRODUCE_SUB_EXTENT(), 1);
  return 1;
}

int vtkAFAMReader::RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector* outV)
{
  vtkInformation* outInfo = outV->GetInformationObject(0);
  auto* output = vtkMultiBlockDataSet::GetData(outV, 0);
  if (!output || !this->FileName || !*this->FileName)
  {
    vtkErrorMacro(<< "No file name set.");
    return 0;
  }
  int piece = 0, numPieces = 1;
  if (outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER()))
  {
    piece = outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER());
    numPieces = outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES());
  }
  try
  {
    // Opening reads and validates the header and the index only, never a payload. A run opens at
    // the step the pipeline's time asks for.
    auto file = afam::AfamFile::open(this->FileName);
    const long long step = vtkAFAMModelTree::StepAtTime(file->stepTimes(), outInfo);
    if (step != 0)
    {
      file = afam::AfamFile::open(this->FileName, step);
    }
    if (file->stepCount() > 1)
    {
      output->GetInformation()->Set(
        vtkDataObject::DATA_TIME_STEP(), file->stepTimes()[static_cast<size_t>(step)]);
    }
    const bool decode = this->DecodeLevel >= 0;
    const double treeShare = decode ? 0.1 : 1.0; // progress: the index is cheap, decoding is not
    vtkAFAMModelTree::Build(
      file->header(),
      file->partition(),
      file->entries(),
      file->path(),
      piece,
      numPieces,
      output,
      [this, treeShare](double f) { this->UpdateProgress(treeShare * f); },
      step);
    vtkImageData* image = vtkImageData::GetData(outV, 1);
    if (image)
    {
      image->Initialize();
    }
    if (image && file->stepCount() > 1)
    {
      image->GetInformation()->Set(
        vtkDataObject::DATA_TIME_STEP(), file->stepTimes()[static_cast<size_t>(step)]);
    }
    if (decode && image)
    {
      int ext[6];
      outV->GetInformationObject(1)->Get(vtkStreamingDemandDrivenPipeline::UPDATE_EXTENT(), ext);
      const afam::LevelGrid grid = afam::levelGrid(file->partition(), this->DecodeLevel);
      double origin[3], spacing[3];
      LevelGeometry(file->header(), grid.dims, origin, spacing);
      image->SetOrigin(origin);
      image->SetSpacing(spacing);
      if (ext[0] <= ext[1] && ext[2] <= ext[3] && ext[4] <= ext[5])
      {
        image->SetExtent(ext);
        vtkNew<vtkFloatArray> values;
        const std::string& name = file->header().scalarName;
        values->SetName(name.empty() ? "scalars" : name.c_str());
        values->SetNumberOfTuples(image->GetNumberOfPoints());
        std::vector<std::string> damaged;
        afam::decodeLevelBox(
          *file,
          this->DecodeLevel,
          { ext[0], ext[2], ext[4] },
          { ext[1], ext[3], ext[5] },
          values->GetPointer(0),
          [this, treeShare](double f) { this->UpdateProgress(treeShare + (1 - treeShare) * f); },
          &damaged);
        // The values the source had: a spline's overshoot would stretch a shared colour map.
        afam::clampToSourceRange(
          *file, values->GetPointer(0), static_cast<size_t>(values->GetNumberOfTuples()));
        image->GetPointData()->SetScalars(values);
        this->ReportDamagedBlocks(damaged, file->path());
      }
    }
  }
  catch (const std::exception& e)
  {
    output->Initialize();
    if (vtkImageData* image = vtkImageData::GetData(outV, 1))
    {
      image->Initialize();
    }
    this->ReportOnce(e.what());
    return 1; // an empty output: the error above says why
  }
  this->LastError.clear();
  return 1;
}

void vtkAFAMReader::ReportDamagedBlocks(const std::vector<std::string>& damaged,
  const std::string& path)
{
  if (damaged.empty())
  {
    return;
  }
  // One warning per decode, however many blocks: the first few in full.
  const size_t shown = std::min<size_t>(damaged.size(), 4);
  std::string text = "Decoded level " + std::to_string(this->DecodeLevel) + ": " +
    std::to_string(damaged.size()) + " damaged micro-model(s), their samples taken from the " +
    "nearest intact level (NaN where none is intact; `afam verify " + path +
    "` lists every damaged micro-model):";
  for (size_t i = 0; i < shown; ++i)
  {
    text += "\n" + damaged[i];
  }
  if (damaged.size() > shown)
  {
    text += "\n... and " + std::to_string(damaged.size() - shown) + " more";
  }
  vtkWarningMacro(<< text);
}

void vtkAFAMReader::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << (this->FileName ? this->FileName : "(none)") << "\n";
  os << indent << "DecodeLevel: " << this->DecodeLevel << "\n";
}
