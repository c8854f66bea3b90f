// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMWriter.h"

#include "vtkAFAMModelTree.h"

#include "afam/format/afam_file.hpp"

#include "vtkErrorCode.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkMultiBlockDataSet.h"
#include "vtkMultiProcessController.h"
#include "vtkObjectFactory.h"
#include "vtkStreamingDemandDrivenPipeline.h"

#include <filesystem>

vtkStandardNewMacro(vtkAFAMWriter);

vtkAFAMWriter::vtkAFAMWriter() = default;

vtkAFAMWriter::~vtkAFAMWriter()
{
  this->SetFileName(nullptr);
}

int vtkAFAMWriter::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkMultiBlockDataSet");
  return 1;
}

vtkTypeBool vtkAFAMWriter::ProcessRequest(vtkInformation* request,
  vtkInformationVector** inputVector,
  vtkInformationVector* outputVector)
{
  vtkMultiProcessController* controller = vtkMultiProcessController::GetGlobalController();
  if (request->Has(vtkStreamingDemandDrivenPipeline::REQUEST_UPDATE_EXTENT()) && controller &&
    controller->GetNumberOfProcesses() > 1)
  {
    // Each rank asks for its own piece, so that an encoder upstream encodes pieces of the image
    // (the default, piece 0 of 1, would give every rank the whole image).
    vtkInformation* in = inputVector[0]->GetInformationObject(0);
    in->Set(
      vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER(), controller->GetLocalProcessId());
    in->Set(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES(),
      controller->GetNumberOfProcesses());
    return 1;
  }
  return this->Superclass::ProcessRequest(request, inputVector, outputVector);
}

void vtkAFAMWriter::WriteData()
{
  namespace fs = std::filesystem;
  if (!this->FileName || !*this->FileName)
  {
    vtkErrorMacro(<< "No file name set.");
    this->SetErrorCode(vtkErrorCode::NoFileNameError);
    return;
  }
  const std::string source =
    vtkAFAMModelTree::FileName(vtkMultiBlockDataSet::SafeDownCast(this->GetInput()));
  vtkMultiProcessController* controller = vtkMultiProcessController::GetGlobalController();
  if (controller && controller->GetLocalProcessId() > 0)
  {
    return; // under MPI rank 0 writes the one file (it holds the encoder's models)
  }
  if (source.empty())
  {
    vtkErrorMacro(<< "The input is not an Adaptive-FAM model set (no "
                  << vtkAFAMModelTree::FileNameArray << " field data).");
    this->SetErrorCode(vtkErrorCode::UnknownError);
    return;
  }
  const std::string tmp = std::string(this->FileName) + ".tmp-afam-writer";
  std::error_code ec;
  try
  {
    // Validate every payload before anything is written.
    auto file = afam::AfamFile::open(source);
    std::vector<float> scratch;
    for (size_t i = 0; i < file->entries().size(); ++i)
    {
      scratch.resize(file->entries()[i].size / sizeof(float) + 1);
      file->readPayload(static_cast<int64_t>(i), scratch.data());
      this->UpdateProgress(
        0.8 * static_cast<double>(i) / static_cast<double>(file->entries().size()));
    }
    if (fs::equivalent(source, this->FileName, ec))
    {
      return; // already there
    }
    fs::copy_file(source, tmp, fs::copy_options::overwrite_existing);
    fs::rename(tmp, this->FileName);
    this->UpdateProgress(1.0);
  }
  catch (const std::exception& e)
  {
    fs::remove(tmp, ec);
    vtkErrorMacro(<< "cannot write '" << this->FileName << "': " << e.what());
    this->SetErrorCode(vtkErrorCode::CannotOpenFileError);
  }
}

void vtkAFAMWriter::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << (this->FileName ? this->FileName : "(none)") << "\n";
}
