// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMReader.h"

#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkMultiBlockDataSet.h"
#include "vtkObjectFactory.h"
#include "vtkStreamingDemandDrivenPipeline.h"

#include <cstring>
#include <fstream>

vtkStandardNewMacro(vtkAFAMReader);

namespace
{
// Placeholder until Core's afam_file.hpp lands: the first bytes of every .afam file.
constexpr char kMagic[4] = { 'A', 'F', 'A', 'M' };

bool HasMagic(const char* filename, std::string& why)
{
  if (!filename || !*filename)
  {
    why = "no file name set";
    return false;
  }
  std::ifstream in(filename, std::ios::binary);
  if (!in)
  {
    why = std::string("cannot open '") + filename + "'";
    return false;
  }
  char head[sizeof(kMagic)] = {};
  in.read(head, sizeof(head));
  if (in.gcount() != sizeof(head) || std::memcmp(head, kMagic, sizeof(kMagic)) != 0)
  {
    why = std::string("'") + filename + "' is not an .afam file (bad magic)";
    return false;
  }
  return true;
}
}

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
  std::string why;
  return HasMagic(filename, why) ? 1 : 0;
}

int vtkAFAMReader::RequestInformation(
  vtkInformation*, vtkInformationVector**, vtkInformationVector*)
{
  std::string why;
  if (!HasMagic(this->FileName, why))
  {
    vtkErrorMacro(<< why);
    return 0;
  }
  return 1;
}

int vtkAFAMReader::RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector* outV)
{
  auto* output = vtkMultiBlockDataSet::GetData(outV, 0);
  if (!output)
  {
    vtkErrorMacro(<< "no output multiblock");
    return 0;
  }
  std::string why;
  if (!HasMagic(this->FileName, why))
  {
    vtkErrorMacro(<< why);
    return 0;
  }
  return 1;
}

void vtkAFAMReader::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << (this->FileName ? this->FileName : "(none)") << "\n";
}
