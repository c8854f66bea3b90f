// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMReader.h"

#include "vtkAFAMModelTree.h"

#include "afam/afam_file.hpp"
#include "afam/errors.hpp"

#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkMultiBlockDataSet.h"
#include "vtkObjectFactory.h"
#include "vtkStreamingDemandDrivenPipeline.h"

vtkStandardNewMacro(vtkAFAMReader);

vtkAFAMReader::vtkAFAMReader()
{
  this->SetNumberOfInputPorts(0);
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
  try
  {
    afam::AfamFile::open(filename);
    return 1;
  }
  catch (const std::exception&)
  {
    return 0;
  }
}

int vtkAFAMReader::RequestInformation(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* outV)
{
  if (!this->FileName || !*this->FileName)
  {
    vtkErrorMacro(<< "No file name set.");
    return 0;
  }
  // Pieces are groups of coarsest blocks (see vtkAFAMModelTree::Build).
  outV->GetInformationObject(0)->Set(CAN_HANDLE_PIECE_REQUEST(), 1);
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
    // Opening reads and validates the header and the index only, never a payload.
    auto file = afam::AfamFile::open(this->FileName);
    vtkAFAMModelTree::Build(file->header(), file->partition(), file->entries(), file->path(), piece,
      numPieces, output, [this](double f) { this->UpdateProgress(f); });
  }
  catch (const std::exception& e)
  {
    output->Initialize();
    vtkErrorMacro(<< e.what());
    return 0;
  }
  return 1;
}

void vtkAFAMReader::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << (this->FileName ? this->FileName : "(none)") << "\n";
}
