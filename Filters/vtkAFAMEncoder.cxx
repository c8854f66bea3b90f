// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMEncoder.h"

#include "vtkAFAMControllerTeam.h"
#include "vtkAFAMDistributedEncode.h"
#include "vtkAFAMMissingSamples.h"
#include "vtkAFAMModelTree.h"

#include "afam/cuda/encode/make_gpu_least_squares.hpp"
#include "afam/cuda/encode/make_gpu_level_sampler.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/encode/encoder.hpp"
#include "afam/encode/pipeline_run.hpp"

#include "vtkDataArray.h"
#include "vtkDataSetAttributes.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkMatrix3x3.h"
#include "vtkMultiBlockDataSet.h"
#include "vtkCommunicator.h"
#include "vtkMultiProcessController.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkStreamingDemandDrivenPipeline.h"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>
#include <signal.h>
#include <unistd.h>

vtkStandardNewMacro(vtkAFAMEncoder);

vtkAFAMEncoder::vtkAFAMEncoder()
  : Run(std::make_unique<afam::PipelineRun>())
{
  this->SetInputArrayToProcess(
    0, 0, 0, vtkDataObject::FIELD_ASSOCIATION_POINTS, vtkDataSetAttributes::SCALARS);
  this->SetValidPointMaskArrayName("vtkValidPointMask");
}

vtkAFAMEncoder::~vtkAFAMEncoder()
{
  this->RemoveModelFile(); // a run under way leaves none (PipelineRun)
  this->SetValidPointMaskArrayName(nullptr);
}

int vtkAFAMEncoder::RequestInformation(vtkInformation*,
  vtkInformationVector** inputVector,
  vtkInformationVector*)
{
  // The output keeps the input's time steps (the executive copies them): a run's output
  // describes the step the time asks for.
  vtkInformation* inInfo = inputVector[0]->GetInformationObject(0);
  std::vector<double> times;
  if (this->EncodeTimeSteps && inInfo->Has(vtkStreamingDemandDrivenPipeline::TIME_STEPS()) &&
    inInfo->Length(vtkStreamingDemandDrivenPipeline::TIME_STEPS()) > 1)
  {
    const double* t = inInfo->Get(vtkStreamingDemandDrivenPipeline::TIME_STEPS());
    times.assign(t, t + inInfo->Length(vtkStreamingDemandDrivenPipeline::TIME_STEPS()));
  }
  this->Run->setTimes(std::move(times)); // other times than the run's drop it
  return 1;
}

int vtkAFAMEncoder::RequestUpdateExtent(vtkInformation*,
  vtkInformationVector** inputVector,
  vtkInformationVector*)
{
  if (!this->EncodesRun())
  {
    return 1; // the time asked of the output, as the executive passes it up
  }
  inputVector[0]->GetInformationObject(0)->Set(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP(),
    this->Run->times()[this->Run->stepToRead()]);
  return 1;
}

bool vtkAFAMEncoder::EncodesRun() const
{
  return this->Run->times().size() > 1;
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
      const bool mask = a && a->GetName() && this->ValidPointMaskArrayName &&
        std::string(a->GetName()) == this->ValidPointMaskArrayName;
      if (a && a->GetNumberOfComponents() == 1 && !mask)
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
  options.boundKind =
    this->BoundKind == BOUND_MAX_ERROR ? afam::BoundKind::MaxError : afam::BoundKind::Rmse;
  static_assert(MODE_ADAPTIVE == static_cast<int>(afam::EncodingMode::Adaptive) &&
      MODE_IN_LEVEL == static_cast<int>(afam::EncodingMode::InLevel) &&
      MODE_FIXED_NCP == static_cast<int>(afam::EncodingMode::Fixed) &&
      MODE_DOWNSAMPLED == static_cast<int>(afam::EncodingMode::Downsampled),
    "the filter's modes are Core's");
  options.mode = static_cast<afam::EncodingMode>(this->Mode);
  options.fixedNcp = this->FixedNcp;
  options.threads = this->NumberOfThreads;
  options.hasMissingValue = this->UseMissingValue;
  options.missingValue = this->MissingValue;
  if (this->Device != DEVICE_CPU)
  {
    options.leastSquares = afam::makeGpuLeastSquares(
      [this](const std::string& why)
      {
        if (this->Device == DEVICE_GPU)
        {
          vtkWarningMacro("Device GPU: " << why << "; encoding on the CPU");
        }
      });
  }
  if (options.leastSquares)
  {
    options.levelSampler = afam::makeGpuLevelSampler([](const std::string&) {});
  }
  this->LastDevice =
    options.leastSquares ? "gpu " + options.leastSquares->description() : std::string("cpu");
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
  if (!stats.aheadFailure.empty())
  {
    vtkWarningMacro(
      "asking the GPU failed (" << stats.aheadFailure << "); the rest was fitted on the CPU");
  }
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

std::string vtkAFAMEncoder::MissingMarksProblem(vtkImageData* input,
  afam::SampleType type,
  const std::string& arrayName,
  vtkAFAMValidMask& mask)
{
  std::string error;
  const char* maskName = this->ValidPointMaskArrayName;
  if (!vtkAFAMFindValidMask(
        input->GetPointData(), maskName, input->GetNumberOfPoints(), mask, error))
  {
    return error;
  }
  if (!mask.Valid && maskName && *maskName && std::string(maskName) != "vtkValidPointMask")
  {
    vtkWarningMacro(<< "the input has no point array '" << maskName
                    << "' (ValidPointMaskArrayName): no mask applied");
  }
  if (!this->UseMissingValue)
  {
    return "";
  }
  return vtkAFAMMissingValueProblem(this->MissingValue, type, arrayName);
}

void vtkAFAMEncoder::KeepRunStatistics(const afam::RunStats& stats)
{
  afam::EncodeStats all; // the run as one: its worst block, its bound, all its bytes
  all.seconds = stats.seconds;
  all.bound = stats.bound;
  all.bytesOut = stats.bytesOut;
  for (const afam::EncodeStats& s : stats.steps)
  {
    all.maxRmse = std::max(all.maxRmse, s.maxRmse);
    all.maxError = std::max(all.maxError, s.maxError);
    all.bytesIn += s.bytesIn;
  }
  this->KeepStatistics(all);
  std::ostringstream report;
  for (size_t k = 0; k < stats.steps.size(); ++k)
  {
    report << (k ? "\n" : "") << "step " << k << ": max_rmse=" << stats.steps[k].maxRmse
           << " references=" << stats.references[k] << " residuals=" << stats.residuals[k]
           << " bound=" << stats.bound;
  }
  this->LastLevelReport = report.str();
}

void vtkAFAMEncoder::BuildOutput(const std::string& path,
  vtkMultiBlockDataSet* output,
  long long step)
{
  this->ModelFile = path;
  auto file = afam::AfamFile::open(path, step);
  vtkAFAMModelTree::Build(
    file->header(),
    file->partition(),
    file->entries(),
    file->path(),
    0,
    1,
    output,
    [this](double f) { this->UpdateProgress(0.95 + 0.05 * f); },
    step);
  if (file->stepCount() > 1)
  {
    output->GetInformation()->Set(
      vtkDataObject::DATA_TIME_STEP(), file->stepTimes()[static_cast<size_t>(step)]);
  }
}

int vtkAFAMEncoder::RequestData(vtkInformation* request,
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
  input->GetExtent(this->LastPieceExtent);
  this->LastRemoteBytesRead = 0;
  vtkMultiProcessController* controller = vtkMultiProcessController::GetGlobalController();
  const bool pieces = controller && controller->GetNumberOfProcesses() > 1;
  const bool run = this->EncodesRun();
  if (!run)
  {
    this->Run->drop();
    this->RemoveModelFile();
  }
  try
  {
    if (run      ? !this->EncodeTimeStep(request, input, inputVector, outputVector, controller)
        : pieces ? !this->EncodeOnRanks(controller, input, inputVector, output)
                 : !this->EncodeWhole(input, inputVector, output))
    {
      request->Remove(vtkStreamingDemandDrivenPipeline::CONTINUE_EXECUTING());
      this->Run->drop();
      return 0;
    }
  }
  catch (const afam::Cancelled&)
  {
    request->Remove(vtkStreamingDemandDrivenPipeline::CONTINUE_EXECUTING());
    output->Initialize();
    this->Run->drop();
    this->RemoveModelFile();
    vtkWarningMacro(<< "encoding cancelled");
    return 0;
  }
  catch (const std::exception& e)
  {
    request->Remove(vtkStreamingDemandDrivenPipeline::CONTINUE_EXECUTING());
    output->Initialize();
    this->Run->drop();
    this->RemoveModelFile();
    vtkErrorMacro(<< e.what());
    return 0;
  }
  return 1;
}

uint32_t vtkAFAMEncoder::InputFingerprint(vtkImageData* input, vtkInformationVector** inputVector)
{
  // A file-series reader executes again for the same time (its inner reader's file name is set
  // anew), so neither the data's nor the pipeline's modification time tells a changed input:
  // the chosen array's bytes do (CRC-32 with the grid and the name; a pass over memory).
  std::string ignored;
  vtkDataArray* array = this->ChooseArray(input, inputVector, ignored);
  vtkAFAMArraySamples samples; // in VTK's standard layout, as encoded
  if (!array || !vtkAFAMGetSamples(array, samples, ignored))
  {
    return 0;
  }
  int dims[3];
  input->GetDimensions(dims);
  double origin[3], spacing[3];
  input->GetOrigin(origin);
  input->GetSpacing(spacing);
  uint32_t crc = afam::crc32(dims, sizeof dims);
  crc = afam::crc32(origin, sizeof origin, crc);
  crc = afam::crc32(spacing, sizeof spacing, crc);
  const std::string name = array->GetName() ? array->GetName() : "";
  crc = afam::crc32(name.data(), name.size(), crc);
  const size_t bytes = static_cast<size_t>(array->GetNumberOfValues()) *
    static_cast<size_t>(afam::sampleTypeSize(samples.Type));
  return afam::crc32(samples.Data, bytes, crc);
}

std::unique_ptr<afam::ArraySource> vtkAFAMEncoder::SourceOf(vtkImageData* input,
  vtkInformationVector** inputVector,
  vtkAFAMArraySamples& samples)
{
  std::string error;
  vtkDataArray* array = this->ChooseArray(input, inputVector, error);
  if (!array)
  {
    vtkErrorMacro(<< error);
    return nullptr;
  }
  int dims[3];
  input->GetDimensions(dims);
  if (array->GetNumberOfTuples() != static_cast<vtkIdType>(dims[0]) * dims[1] * dims[2])
  {
    vtkErrorMacro(<< "array '" << (array->GetName() ? array->GetName() : "") << "' has "
                  << array->GetNumberOfTuples() << " values for " << dims[0] << "x" << dims[1]
                  << "x" << dims[2] << " points");
    return nullptr;
  }
  if (!vtkAFAMGetSamples(array, samples, error))
  {
    vtkErrorMacro(<< error);
    return nullptr;
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
  return std::make_unique<afam::ArraySource>(samples.Data,
    samples.Type,
    afam::Index3{ dims[0], dims[1], dims[2] },
    array->GetName() ? array->GetName() : "scalars",
    std::array<double, 3>{ origin[0], origin[1], origin[2] },
    std::array<double, 3>{ spacing[0], spacing[1], spacing[2] });
}

struct vtkAFAMEncoder::MarkedInput
{
  vtkAFAMArraySamples Samples; ///< what the sources read, kept while they do
  std::unique_ptr<afam::ArraySource> Values;
  vtkAFAMValidMask Mask;
  std::unique_ptr<vtkAFAMMarkedSource> Marked;
};

std::unique_ptr<vtkAFAMEncoder::MarkedInput> vtkAFAMEncoder::MarkedSourceOf(vtkImageData* input,
  vtkInformationVector** inputVector,
  bool useValue)
{
  auto in = std::make_unique<MarkedInput>();
  in->Values = this->SourceOf(input, inputVector, in->Samples);
  if (!in->Values)
  {
    return nullptr;
  }
  const std::string problem =
    this->MissingMarksProblem(input, in->Samples.Type, in->Values->name(), in->Mask);
  if (!problem.empty())
  {
    vtkErrorMacro(<< problem);
    return nullptr;
  }
  in->Marked = std::make_unique<vtkAFAMMarkedSource>(
    *in->Values, in->Mask.Valid, useValue, this->MissingValue, in->Samples.Type);
  return in;
}

bool vtkAFAMEncoder::EncodeWhole(vtkImageData* input,
  vtkInformationVector** inputVector,
  vtkMultiBlockDataSet* output)
{
  std::unique_ptr<MarkedInput> marked =
    this->MarkedSourceOf(input, inputVector, this->UseMissingValue);
  if (!marked)
  {
    return false;
  }
  const std::string path = NewModelPath();
  this->KeepStatistics(afam::encodeVolume(marked->Marked->Source(), this->MakeOptions(), path));
  if (marked->Marked->ValueNeverFound())
  {
    vtkWarningMacro(<< vtkAFAMValueNeverFound(this->MissingValue, marked->Values->name()));
  }
  this->BuildOutput(path, output);
  return true;
}

bool vtkAFAMEncoder::EncodeTimeStep(vtkInformation* request,
  vtkImageData* input,
  vtkInformationVector** inputVector,
  vtkInformationVector* outputVector,
  vtkMultiProcessController* controller)
{
  if (this->RunIsCurrent(input, inputVector, controller))
  {
    this->BuildRunOutput(outputVector); // the step the output's time asks for
    return true;
  }
  if (!this->Run->underWay() && !this->StartRun(input))
  {
    request->Set(vtkStreamingDemandDrivenPipeline::CONTINUE_EXECUTING(), 1);
    return true; // this input is another step's: the next execution gets the first
  }
  std::string arrayName;
  if (!this->AddRunStep(input, inputVector, controller, arrayName))
  {
    return false;
  }
  if (!this->Run->complete())
  {
    request->Set(vtkStreamingDemandDrivenPipeline::CONTINUE_EXECUTING(), 1);
    return true;
  }
  request->Remove(vtkStreamingDemandDrivenPipeline::CONTINUE_EXECUTING());
  this->FinishRun(input, inputVector, controller, arrayName);
  this->BuildRunOutput(outputVector);
  return true;
}

bool vtkAFAMEncoder::RunIsCurrent(vtkImageData* input,
  vtkInformationVector** inputVector,
  vtkMultiProcessController* controller)
{
  const afam::RunOrigin* origin = this->Run->finishedFrom();
  int current = origin && origin->settings == this->GetMTime() &&
    origin->input == this->InputFingerprint(input, inputVector);
  if (controller && controller->GetNumberOfProcesses() > 1)
  {
    int all = current; // every rank encodes again when one's piece changed
    controller->AllReduce(&current, &all, 1, vtkCommunicator::MIN_OP);
    current = all;
  }
  return current != 0;
}

bool vtkAFAMEncoder::StartRun(vtkImageData* input)
{
  // A new run (the input or a setting changed), from the first step.
  this->RemoveModelFile();
  vtkInformation* info = input->GetInformation();
  const double time = info->Has(vtkDataObject::DATA_TIME_STEP())
    ? info->Get(vtkDataObject::DATA_TIME_STEP())
    : std::numeric_limits<double>::quiet_NaN(); // not said: taken as the first step
  if (!this->Run->readyToStart(time))
  {
    return false;
  }
  const std::string path = NewModelPath();
  this->Run->start(path, this->MakeOptions());
  this->Run->setProgress( // fractions of the whole run
    [this](double f)
    {
      this->UpdateProgress(0.95 * f);
      return !this->CheckAbort();
    });
  return true;
}

bool vtkAFAMEncoder::AddRunStep(vtkImageData* input,
  vtkInformationVector** inputVector,
  vtkMultiProcessController* controller,
  std::string& arrayName)
{
  afam::PipelineRun& run = *this->Run;
  if (controller && controller->GetNumberOfProcesses() > 1)
  {
    const vtkAFAMPiecesEncoded done = this->EncodePieces(controller,
      input,
      inputVector,
      [&run](afam::VolumeSource& step, afam::EncodeTeam& team) { return run.addStep(step, team); });
    run.noteFillValue(done.missingValueFound);
    arrayName = done.arrayName;
    return true;
  }
  std::unique_ptr<MarkedInput> marked =
    this->MarkedSourceOf(input, inputVector, this->UseMissingValue);
  if (!marked)
  {
    return false;
  }
  run.addStep(marked->Marked->Source());
  run.noteFillValue(!marked->Marked->ValueNeverFound());
  arrayName = marked->Values->name();
  return true;
}

void vtkAFAMEncoder::FinishRun(vtkImageData* input,
  vtkInformationVector** inputVector,
  vtkMultiProcessController* controller,
  const std::string& arrayName)
{
  const bool pieces = controller && controller->GetNumberOfProcesses() > 1;
  const bool first = !controller || controller->GetLocalProcessId() == 0;
  if (this->Run->fillValueNeverFound() && first)
  {
    vtkWarningMacro(<< vtkAFAMValueNeverFound(this->MissingValue, arrayName) << " (at every step)");
  }
  vtkAFAMControllerTeam team(controller);
  afam::SoloTeam solo;
  const afam::RunOrigin origin{ this->GetMTime(), this->InputFingerprint(input, inputVector) };
  this->KeepRunStatistics(
    this->Run->commit(pieces ? static_cast<afam::EncodeTeam&>(team) : solo, origin));
  if (first) // the one file
  {
    this->ModelFile = this->Run->path();
  }
}

void vtkAFAMEncoder::BuildRunOutput(vtkInformationVector* outputVector)
{
  if (!this->ModelFile.empty()) // rank 0 holds the file
  {
    this->BuildOutput(this->ModelFile,
      vtkMultiBlockDataSet::GetData(outputVector, 0),
      vtkAFAMModelTree::StepAtTime(this->Run->times(), outputVector->GetInformationObject(0)));
  }
}

vtkAFAMPiecesEncoded vtkAFAMEncoder::EncodePieces(vtkMultiProcessController* controller,
  vtkImageData* input,
  vtkInformationVector** inputVector,
  const vtkAFAMTeamEncode& encode)
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
  vtkAFAMValidMask mask; // this piece's, checked with the array (every rank agrees on errors)
  afam::SampleType type{};
  if (array && vtkAFAMSampleTypeOf(array->GetDataType(), type))
  {
    error =
      this->MissingMarksProblem(input, type, array->GetName() ? array->GetName() : "scalars", mask);
  }
  vtkAFAMPieceMarks marks;
  marks.Valid = mask.Valid;
  marks.UseValue = this->UseMissingValue;
  marks.Value = this->MissingValue;
  if (controller->GetLocalProcessId() == 0 && input->GetDirectionMatrix() &&
    !input->GetDirectionMatrix()->IsIdentity())
  {
    vtkWarningMacro(<< "the input's direction matrix is ignored: .afam volumes are axis-aligned");
  }
  const vtkAFAMPiecesEncoded done =
    vtkAFAMEncodePieces(controller, input, array, error, whole, marks, encode);
  std::copy(done.pieceExtent, done.pieceExtent + 6, this->LastPieceExtent);
  this->LastRemoteBytesRead = static_cast<double>(done.remoteBytesRead);
  const bool oneVolume = !this->Run->underWay(); // a run warns once, after its last step
  if (marks.UseValue && oneVolume && !done.missingValueFound &&
    controller->GetLocalProcessId() == 0)
  {
    vtkWarningMacro(<< vtkAFAMValueNeverFound(this->MissingValue, done.arrayName));
  }
  return done;
}

bool vtkAFAMEncoder::EncodeOnRanks(vtkMultiProcessController* controller,
  vtkImageData* input,
  vtkInformationVector** inputVector,
  vtkMultiBlockDataSet* output)
{
  const std::string path = NewModelPath();
  const afam::EncoderOptions options = this->MakeOptions();
  const vtkAFAMPiecesEncoded done = this->EncodePieces(controller,
    input,
    inputVector,
    [&options, &path](afam::VolumeSource& volume, afam::EncodeTeam& team)
    { return afam::encodeVolume(volume, options, path, team); });
  this->KeepStatistics(done.stats);
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
  os << indent << "BoundKind: " << this->BoundKind << "\n";
  os << indent << "Levels: " << this->Levels << "\n";
  os << indent << "BlocksPerAxis: " << this->BlocksPerAxis << "\n";
  os << indent << "Degree: " << this->Degree << "\n";
  os << indent << "Mode: " << this->Mode << "\n";
  os << indent << "FixedNcp: " << this->FixedNcp << "\n";
  os << indent << "NumberOfThreads: " << this->NumberOfThreads << "\n";
  os << indent << "Device: " << this->Device << " (last used: " << this->LastDevice << ")\n";
  os << indent << "EncodeTimeSteps: " << this->EncodeTimeSteps << "\n";
  os << indent << "ValidPointMaskArrayName: "
     << (this->ValidPointMaskArrayName ? this->ValidPointMaskArrayName : "(none)") << "\n";
  os << indent << "UseMissingValue: " << this->UseMissingValue << "\n";
  os << indent << "MissingValue: " << this->MissingValue << "\n";
  os << indent << "ModelFile: " << this->ModelFile << "\n";
  os << indent << "LastEncodeSeconds: " << this->LastEncodeSeconds << "\n";
  os << indent << "LastMaxRmse: " << this->LastMaxRmse << "\n";
  os << indent << "LastCompressionRatio: " << this->LastCompressionRatio << "\n";
  os << indent << "LastPieceExtent: " << this->LastPieceExtent[0] << " " << this->LastPieceExtent[1]
     << " " << this->LastPieceExtent[2] << " " << this->LastPieceExtent[3] << " "
     << this->LastPieceExtent[4] << " " << this->LastPieceExtent[5] << "\n";
  os << indent << "LastRemoteBytesRead: " << this->LastRemoteBytesRead << "\n";
}
