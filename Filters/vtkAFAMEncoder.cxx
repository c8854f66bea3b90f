// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMEncoder.h"

#include "vtkAFAMDistributedEncode.h"
#include "vtkAFAMModelTree.h"

#include "afam/format/afam_file.hpp"
#include "afam/encode/encoder.hpp"

#include "vtkDataArray.h"
#include "vtkDataSetAttributes.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkMatrix3x3.h"
#include "vtkMultiBlockDataSet.h"
#include "vtkMultiProcessController.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkStreamingDemandDrivenPipeline.h"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>
#include <signal.h>
#include <unistd.h>

vtkStandardNewMacro(vtkAFAMEncoder);

vtkAFAMEncoder::vtkAFAMEncoder()
{
  this->SetInputArrayToProcess(
    0, 0, 0, vtkDataObject::FIELD_ASSOCIATION_POINTS, vtkDataSetAttributes::SCALARS);
}

vtkAFAMEncoder::~vtkAFAMEncoder()
{
  this->RemoveModelFile();
}

void vtkAFAMEncoder::RemoveModelFile()
{
  if (!this->ModelFile.empty())
  {
    std::error_code ignored;
    std::filesystem::remove(this->ModelFile, ignored);
    this->ModelFile.clear();
  }
}

int vtkAFAMEncoder::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkImageData");
  return 1;
}

vtkDataArray* vtkAFAMEncoder::ChooseArray(vtkImageData* input,
  vtkInformationVector** inputVector,
  std::string& error)
{
  vtkInformation* selection = this->GetInputArrayInformation(0);
  const char* name = selection && selection->Has(vtkDataObject::FIELD_NAME())
    ? selection->Get(vtkDataObject::FIELD_NAME())
    : nullptr;
  vtkPointData* pd = input->GetPointData();
  vtkDataArray* array = nullptr;
  if (name && *name)
  {
    array = this->GetInputArrayToProcess(0, inputVector);
  }
  else // no name: the active scalars, else the only one-component point array
  {
    array = pd->GetScalars();
    std::vector<vtkDataArray*> single;
    for (int i = 0; i < pd->GetNumberOfArrays(); ++i)
    {
      vtkDataArray* a = pd->GetArray(i);
      if (a && a->GetNumberOfComponents() == 1)
      {
        single.push_back(a);
      }
    }
    if (!array && single.size() == 1)
    {
      array = single[0];
    }
  }
  if (array && array->GetNumberOfComponents() == 1)
  {
    return array;
  }
  std::string candidates; // the arrays the encoder could take
  afam::SampleType type{};
  for (int i = 0; i < pd->GetNumberOfArrays(); ++i)
  {
    vtkDataArray* a = pd->GetArray(i);
    if (a && a->GetNumberOfComponents() == 1 && vtkAFAMSampleTypeOf(a->GetDataType(), type))
    {
      candidates += std::string(candidates.empty() ? "" : ", ") + "'" +
        (a->GetName() ? a->GetName() : "(unnamed)") + "'";
    }
  }
  std::ostringstream msg;
  vtkAbstractArray* other = name && *name && !array ? pd->GetAbstractArray(name) : nullptr;
  if (other && other->GetNumberOfComponents() == 1) // strings or variants: not numbers
  {
    msg << vtkAFAMRefusedType(other) << "; one-component point arrays it can take: "
        << (candidates.empty() ? "none" : candidates);
  }
  else if (name && *name && !array && !other)
  {
    msg << "the input has no point-data array '" << name << "'; one-component point "
        << "arrays: " << (candidates.empty() ? "none" : candidates);
  }
  else if (array || other)
  {
    vtkAbstractArray* chosen = array ? array : other;
    msg << "array '" << (chosen->GetName() ? chosen->GetName() : "") << "' has "
        << chosen->GetNumberOfComponents() << " components (of " << chosen->GetDataTypeAsString()
        << " values); choose one of the "
        << "one-component point arrays: " << (candidates.empty() ? "none" : candidates);
  }
  else
  {
    msg << "no array chosen and no active point scalars; choose one of the "
        << "one-component point arrays: " << (candidates.empty() ? "none" : candidates);
  }
  error = msg.str();
  return nullptr;
}

afam::EncoderOptions vtkAFAMEncoder::MakeOptions()
{
  afam::EncoderOptions options;
  options.levels = this->Levels;
  options.blocksPerAxis = this->BlocksPerAxis;
  options.degree = this->Degree;
  options.errorBound = this->ErrorBound;
  options.relativeBound = this->RelativeBound;
  static_assert(MODE_ADAPTIVE == static_cast<int>(afam::EncodingMode::Adaptive) &&
      MODE_IN_LEVEL == static_cast<int>(afam::EncodingMode::InLevel) &&
      MODE_FIXED_NCP == static_cast<int>(afam::EncodingMode::Fixed) &&
      MODE_DOWNSAMPLED == static_cast<int>(afam::EncodingMode::Downsampled),
    "the filter's modes are Core's");
  options.mode = static_cast<afam::EncodingMode>(this->Mode);
  options.fixedNcp = this->FixedNcp;
  options.threads = this->NumberOfThreads;
  options.progress = [this](double f)
  {
    this->UpdateProgress(0.95 * f);
    return !this->CheckAbort();
  };
  return options;
}

namespace
{
/// Removes the model files that encoders of processes no longer running left in `dir` (a pvserver
/// or pvbatch that was killed never destroys its filters). Files of live processes, or of other
/// users (not removable), stay.
void RemoveOrphanModelFiles(const std::filesystem::path& dir)
{
  std::error_code ec;
  for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
  {
    const std::string name = it->path().filename().string();
    long pid = 0;
    int counter = 0, used = 0;
    if (std::sscanf(name.c_str(), "afam-encoder-%ld-%d.afam%n", &pid, &counter, &used) != 2 ||
      used != static_cast<int>(name.size()) || pid <= 0 || pid == static_cast<long>(::getpid()))
    {
      continue;
    }
    if (::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH)
    {
      std::error_code ignored;
      std::filesystem::remove(it->path(), ignored);
    }
  }
}
}

std::string vtkAFAMEncoder::NewModelPath()
{
  static std::atomic<int> counter{ 0 };
  static std::once_flag swept;
  const std::filesystem::path dir = std::filesystem::temp_directory_path();
  std::call_once(swept, [&dir] { RemoveOrphanModelFiles(dir); });
  return (dir /
    ("afam-encoder-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".afam"))
    .string();
}

void vtkAFAMEncoder::KeepStatistics(const afam::EncodeStats& stats)
{
  this->LastEncodeSeconds = stats.seconds;
  this->LastMaxRmse = stats.maxRmse;
  this->LastMaxError = stats.maxError;
  this->LastBound = stats.bound;
  std::ostringstream report;
  for (size_t l = 0; l < stats.levels.size(); ++l)
  {
    report << (l ? "\n" : "") << "level " << l << ": max_rmse=" << stats.levels[l].maxRmse
           << " max_error=" << stats.levels[l].maxError << " bound=" << stats.bound;
  }
  this->LastLevelReport = report.str();
  vtkDebugMacro(<< "encoded within the bound " << stats.bound << ":\n" << this->LastLevelReport);
  this->LastCompressionRatio = stats.bytesOut > 0
    ? static_cast<double>(stats.bytesIn) / static_cast<double>(stats.bytesOut)
    : 0;
}

void vtkAFAMEncoder::BuildOutput(const std::string& path, vtkMultiBlockDataSet* output)
{
  this->ModelFile = path;
  auto file = afam::AfamFile::open(path);
  vtkAFAMModelTree::Build(file->header(),
    file->partition(),
    file->entries(),
    file->path(),
    0,
    1,
    output,
    [this](double f) { this->UpdateProgress(0.95 + 0.05 * f); });
}

int vtkAFAMEncoder::RequestData(vtkInformation*,
  vtkInformationVector** inputVector,
  vtkInformationVector* outputVector)
{
  vtkImageData* input = vtkImageData::GetData(inputVector[0], 0);
  vtkMultiBlockDataSet* output = vtkMultiBlockDataSet::GetData(outputVector, 0);
  if (!input || !output)
  {
    vtkErrorMacro(<< "needs a vtkImageData input");
    return 0;
  }
  this->RemoveModelFile();
  input->GetExtent(this->LastPieceExtent);
  this->LastRemoteBytesRead = 0;
  vtkMultiProcessController* controller = vtkMultiProcessController::GetGlobalController();
  const bool pieces = controller && controller->GetNumberOfProcesses() > 1;
  try
  {
    if (pieces ? !this->EncodePieces(controller, input, inputVector, output)
               : !this->EncodeWhole(input, inputVector, output))
    {
      return 0;
    }
  }
  catch (const afam::Cancelled&)
  {
    output->Initialize();
    this->RemoveModelFile();
    vtkWarningMacro(<< "encoding cancelled");
    return 0;
  }
  catch (const std::exception& e)
  {
    output->Initialize();
    this->RemoveModelFile();
    vtkErrorMacro(<< e.what());
    return 0;
  }
  return 1;
}

bool vtkAFAMEncoder::EncodeWhole(vtkImageData* input,
  vtkInformationVector** inputVector,
  vtkMultiBlockDataSet* output)
{
  std::string error;
  vtkDataArray* array = this->ChooseArray(input, inputVector, error);
  if (!array)
  {
    vtkErrorMacro(<< error);
    return false;
  }
  int dims[3];
  input->GetDimensions(dims);
  if (array->GetNumberOfTuples() != static_cast<vtkIdType>(dims[0]) * dims[1] * dims[2])
  {
    vtkErrorMacro(<< "array '" << (array->GetName() ? array->GetName() : "") << "' has "
                  << array->GetNumberOfTuples() << " values for " << dims[0] << "x" << dims[1]
                  << "x" << dims[2] << " points");
    return false;
  }
  vtkAFAMArraySamples samples;
  if (!vtkAFAMGetSamples(array, samples, error))
  {
    vtkErrorMacro(<< error);
    return false;
  }
  // The file's origin is the world position of the first sample that arrived: the image's origin
  // is that of index (0, 0, 0), and the extent (the whole extent's or a sub-extent's) may start
  // elsewhere, e.g. at -20 for ParaView's Wavelet.
  int extent[6];
  double origin[3], spacing[3];
  input->GetExtent(extent);
  input->GetOrigin(origin);
  input->GetSpacing(spacing);
  for (int a = 0; a < 3; ++a)
  {
    origin[a] += static_cast<double>(extent[2 * a]) * spacing[a];
  }
  if (input->GetDirectionMatrix() && !input->GetDirectionMatrix()->IsIdentity())
  {
    vtkWarningMacro(<< "the input's direction matrix is ignored: .afam volumes are axis-aligned");
  }
  // The array in its own type: the encoder converts the planes it reads, as VTK would
  // (static_cast).
  afam::ArraySource source(samples.Data,
    samples.Type,
    afam::Index3{ dims[0], dims[1], dims[2] },
    array->GetName() ? array->GetName() : "scalars",
    { origin[0], origin[1], origin[2] },
    { spacing[0], spacing[1], spacing[2] });
  const std::string path = NewModelPath();
  this->KeepStatistics(afam::encodeVolume(source, this->MakeOptions(), path));
  this->BuildOutput(path, output);
  return true;
}

bool vtkAFAMEncoder::EncodePieces(vtkMultiProcessController* controller,
  vtkImageData* input,
  vtkInformationVector** inputVector,
  vtkMultiBlockDataSet* output)
{
  vtkInformation* inInfo = inputVector[0]->GetInformationObject(0);
  int whole[6];
  input->GetExtent(whole);
  if (inInfo->Has(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT()))
  {
    inInfo->Get(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), whole);
  }
  std::string error;
  vtkDataArray* array =
    input->GetNumberOfPoints() > 0 ? this->ChooseArray(input, inputVector, error) : nullptr;
  if (controller->GetLocalProcessId() == 0 && input->GetDirectionMatrix() &&
    !input->GetDirectionMatrix()->IsIdentity())
  {
    vtkWarningMacro(<< "the input's direction matrix is ignored: .afam volumes are axis-aligned");
  }
  const std::string path = NewModelPath();
  const vtkAFAMPiecesEncoded done =
    vtkAFAMEncodePieces(controller, input, array, error, whole, this->MakeOptions(), path);
  this->KeepStatistics(done.stats);
  std::copy(done.pieceExtent, done.pieceExtent + 6, this->LastPieceExtent);
  this->LastRemoteBytesRead = static_cast<double>(done.remoteBytesRead);
  if (controller->GetLocalProcessId() == 0) // the one file; the other ranks' outputs stay empty
  {
    this->BuildOutput(path, output);
  }
  return true;
}

void vtkAFAMEncoder::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "ErrorBound: " << this->ErrorBound << "\n";
  os << indent << "RelativeBound: " << this->RelativeBound << "\n";
  os << indent << "Levels: " << this->Levels << "\n";
  os << indent << "BlocksPerAxis: " << this->BlocksPerAxis << "\n";
  os << indent << "Degree: " << this->Degree << "\n";
  os << indent << "Mode: " << this->Mode << "\n";
  os << indent << "FixedNcp: " << this->FixedNcp << "\n";
  os << indent << "NumberOfThreads: " << this->NumberOfThreads << "\n";
  os << indent << "ModelFile: " << this->ModelFile << "\n";
  os << indent << "LastEncodeSeconds: " << this->LastEncodeSeconds << "\n";
  os << indent << "LastMaxRmse: " << this->LastMaxRmse << "\n";
  os << indent << "LastCompressionRatio: " << this->LastCompressionRatio << "\n";
  os << indent << "LastPieceExtent: " << this->LastPieceExtent[0] << " " << this->LastPieceExtent[1]
     << " " << this->LastPieceExtent[2] << " " << this->LastPieceExtent[3] << " "
     << this->LastPieceExtent[4] << " " << this->LastPieceExtent[5] << "\n";
  os << indent << "LastRemoteBytesRead: " << this->LastRemoteBytesRead << "\n";
}
