// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMVolumeRepresentation.h"

#include "afam/ranks/same_file.hpp"

#include "vtkAFAMModelTree.h"
#include "vtkAFAMVolumeMapper.h"

#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkPointData.h"

#include <algorithm>
#include "vtkInformationVector.h"
#include "vtkMath.h"
#include "vtkMultiBlockDataSet.h"
#include "vtkMultiProcessController.h"
#include "vtkMultiProcessStream.h"
#include "vtkObjectFactory.h"
#include "vtkOutlineSource.h"
#include "vtkPVLODVolume.h"
#include "vtkPVRenderView.h"
#include "vtkPolyDataMapper.h"
#include "vtkRenderer.h"
#include "vtkVolumeProperty.h"

vtkStandardNewMacro(vtkAFAMVolumeRepresentation);

vtkAFAMVolumeRepresentation::vtkAFAMVolumeRepresentation()
{
  this->Actor->SetProperty(this->Property);
  this->Actor->SetMapper(this->Mapper);
  this->Actor->SetLODMapper(this->OutlineMapper);
  vtkMath::UninitializeBounds(this->DataBounds);
}

vtkAFAMVolumeRepresentation::~vtkAFAMVolumeRepresentation() = default;

int vtkAFAMVolumeRepresentation::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkMultiBlockDataSet");
  info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
  return 1;
}

int vtkAFAMVolumeRepresentation::RequestData(vtkInformation* request,
  vtkInformationVector** inputVector,
  vtkInformationVector* outputVector)
{
  vtkMath::UninitializeBounds(this->DataBounds);
  this->FileName.clear();
  long long step = 0;
  if (inputVector[0]->GetNumberOfInformationObjects() == 1)
  {
    auto* tree = vtkMultiBlockDataSet::GetData(inputVector[0], 0);
    this->FileName = vtkAFAMModelTree::FileName(tree);
    step = vtkAFAMModelTree::Step(tree); // the step of a run the view's time chose
    // An empty tree is a reader's or encoder's failed output: it has said what went wrong.
    if (this->FileName.empty() && tree && tree->GetNumberOfBlocks() > 0)
    {
      vtkErrorMacro(<< "The input is not an Adaptive-FAM model set (no "
                    << vtkAFAMModelTree::FileNameArray << " field data).");
    }
  }
  // Every rank renders its own box of the volume (see class documentation).
  auto* controller = vtkMultiProcessController::GetGlobalController();
  const int ranks = controller ? std::max(1, controller->GetNumberOfProcesses()) : 1;
  const int rank = controller ? controller->GetLocalProcessId() : 0;
  this->RendersHere = !this->FileName.empty();
  this->Mapper->SetFileName(this->RendersHere ? this->FileName.c_str() : nullptr);
  this->Mapper->SetTimeStep(step);
  this->Mapper->SetRank(rank, ranks);
  this->Actor->SetVisibility(this->GetVisibility() && this->RendersHere);
  vtkMath::UninitializeBounds(this->DataBounds);
  vtkMath::UninitializeBounds(this->RankBounds);
  if (this->RendersHere)
  {
    std::copy_n(this->Mapper->GetBounds(), 6, this->DataBounds); // the file's header
    if (vtkMath::AreBoundsInitialized(this->DataBounds) &&
      !this->Mapper->GetRankBounds(this->RankBounds))
    {
      // More ranks than finest blocks: this rank draws nothing; a flat box at the volume's
      // corner keeps the ordering of the others' boxes well defined.
      for (int a = 0; a < 3; ++a)
      {
        this->RankBounds[2 * a] = this->RankBounds[2 * a + 1] = this->DataBounds[2 * a + 1];
      }
    }
  }
  if (vtkMath::AreBoundsInitialized(this->DataBounds))
  {
    this->OutlineSource->SetBounds(this->DataBounds);
    this->OutlineSource->Update();
    this->StandIn->SetDimensions(2, 2, 2);
    this->StandIn->SetOrigin(this->DataBounds[0], this->DataBounds[2], this->DataBounds[4]);
    this->StandIn->SetSpacing(std::max(1e-12, this->DataBounds[1] - this->DataBounds[0]),
      std::max(1e-12, this->DataBounds[3] - this->DataBounds[2]),
      std::max(1e-12, this->DataBounds[5] - this->DataBounds[4]));
    vtkNew<vtkFloatArray> scalars;
    scalars->SetName("AFAM_StandIn");
    scalars->SetNumberOfTuples(8);
    scalars->FillValue(0.f);
    this->StandIn->GetPointData()->SetScalars(scalars);
  }
  return this->Superclass::RequestData(request, inputVector, outputVector);
}

int vtkAFAMVolumeRepresentation::ProcessViewRequest(vtkInformationRequestKey* request_type,
  vtkInformation* inInfo,
  vtkInformation* outInfo)
{
  if (!this->Superclass::ProcessViewRequest(request_type, inInfo, outInfo))
  {
    return 0;
  }
  if (request_type == vtkPVView::REQUEST_UPDATE())
  {
    this->AgreeOnFile();
    // Only the outline travels through the delivery path; the mapper reads the file itself.
    vtkPVView::SetPiece(inInfo, this, this->OutlineSource->GetOutputDataObject(0));
    // The volume can only be drawn where the .afam file is: on the server. ParaView offers two
    // ways to get a client-server view right. (1) Deliver the data to the client: below the
    // remote-render threshold the client renders locally from what the delivery path brought,
    // so the client would have to receive the micro-models (the whole point of the format is
    // that they stay on disk near the data and stream per view) or open the server's file
    // itself (which it may not see). (2) Declare that this representation needs distributed
    // rendering: the view then renders on the server ranks and ships the composited image,
    // whatever the threshold, as ParaView's own image volume representation does. We take
    // (2). Builtin mode and one-process pvbatch ignore the request, so they are unchanged.
    vtkPVRenderView::SetRequiresDistributedRendering(inInfo, this, true);
    outInfo->Set(vtkPVRenderView::NEED_ORDERED_COMPOSITING(), 1);
    // Each rank's geometry is its box (their union is the volume, which the view's camera and
    // clipping range see), and the boxes are what ordered compositing sorts. Every rank declares
    // both, also a rank that draws nothing (the outline's box, else a flat one at the origin),
    // since ParaView's ordering of the ranks is collective and takes the same branch on every
    // rank only then.
    static const double nothing[6] = { 0, 0, 0, 0, 0, 0 };
    const double* box = (this->RendersHere && vtkMath::AreBoundsInitialized(this->RankBounds))
      ? this->RankBounds
      : vtkMath::AreBoundsInitialized(this->DataBounds) ? this->DataBounds
                                                        : nothing;
    vtkPVRenderView::SetGeometryBounds(inInfo, this, box);
    vtkPVRenderView::SetOrderedCompositingConfiguration(
      inInfo, this, vtkPVRenderView::USE_BOUNDS_FOR_REDISTRIBUTION, box);
  }
  else if (request_type == vtkPVView::REQUEST_UPDATE_LOD())
  {
    // Interaction (the LOD pass) must render on the server too, for the same reason.
    vtkPVRenderView::SetRequiresDistributedRenderingLOD(inInfo, this, true);
  }
  else if (request_type == vtkPVView::REQUEST_RENDER())
  {
    vtkDataObject* outline = vtkPVView::GetDeliveredPiece(inInfo, this);
    this->OutlineMapper->SetInputDataObject(outline);
    // vtkPVLODVolume::CanRender() renders a vtkVolumeMapper only when its input is image data
    // with scalars: a 2x2x2 stand-in spanning the volume (the mapper reads the .afam file).
    this->Mapper->SetInputDataObject(this->StandIn);
    this->Actor->SetMapper(this->Mapper);
  }
  return 1;
}

void vtkAFAMVolumeRepresentation::AgreeOnFile()
{
  // The ranks of a parallel view must draw one file (their boxes come from its index): each says
  // what it opened, all learn what the others did, and a disagreement hides the volume on every
  // rank, with one error naming the ranks and the path. A view's update is collective: every
  // rank is here, whatever its reader did.
  auto* controller = vtkMultiProcessController::GetGlobalController();
  const int ranks = controller ? controller->GetNumberOfProcesses() : 1;
  if (ranks < 2)
  {
    return;
  }
  const unsigned long long mine = this->FileName.empty() ? 0 : this->Mapper->GetFileFingerprint();
  std::vector<unsigned long long> all(static_cast<size_t>(ranks), 0);
  controller->AllGather(&mine, all.data(), 1);
  // The path as rank 0 names it (a rank whose reader failed has none), for the same sentence on
  // every rank.
  vtkMultiProcessStream name;
  if (controller->GetLocalProcessId() == 0)
  {
    name << (this->FileName.empty() ? std::string("the file") : this->FileName);
  }
  controller->Broadcast(name, 0);
  std::string path;
  name >> path;
  const bool anyFile =
    std::any_of(all.begin(), all.end(), [](unsigned long long f) { return f != 0; });
  const std::string problem = anyFile
    ? afam::ranksFileDisagreement(std::vector<uint64_t>(all.begin(), all.end()), path)
    : std::string(); // no rank has a file: the input's own error said why
  if (!problem.empty())
  {
    if (problem != this->RanksProblem)
    {
      vtkErrorMacro(<< "rank " << controller->GetLocalProcessId() << " of " << ranks << ": "
                    << problem);
    }
    this->RendersHere = false;
    this->Actor->SetVisibility(false);
  }
  this->RanksProblem = problem;
}

void vtkAFAMVolumeRepresentation::SetVisibility(bool visible)
{
  this->Superclass::SetVisibility(visible);
  this->Actor->SetVisibility(visible && this->RendersHere);
}

bool vtkAFAMVolumeRepresentation::AddToView(vtkView* view)
{
  if (auto* rview = vtkPVRenderView::SafeDownCast(view))
  {
    rview->GetRenderer()->AddActor(this->Actor);
    return this->Superclass::AddToView(view);
  }
  return false;
}

bool vtkAFAMVolumeRepresentation::RemoveFromView(vtkView* view)
{
  if (auto* rview = vtkPVRenderView::SafeDownCast(view))
  {
    rview->GetRenderer()->RemoveActor(this->Actor);
    return this->Superclass::RemoveFromView(view);
  }
  return false;
}

void vtkAFAMVolumeRepresentation::SetShade(bool v)
{
  this->Property->SetShade(v);
}
void vtkAFAMVolumeRepresentation::SetAmbient(double v)
{
  this->Property->SetAmbient(v);
}
void vtkAFAMVolumeRepresentation::SetDiffuse(double v)
{
  this->Property->SetDiffuse(v);
}
void vtkAFAMVolumeRepresentation::SetSpecular(double v)
{
  this->Property->SetSpecular(v);
}
void vtkAFAMVolumeRepresentation::SetSpecularPower(double v)
{
  this->Property->SetSpecularPower(v);
}
void vtkAFAMVolumeRepresentation::SetLodPolicy(int v)
{
  this->Mapper->SetLodPolicy(v);
}
void vtkAFAMVolumeRepresentation::SetLodPixelBudget(double v)
{
  this->Mapper->SetLodPixelBudget(v);
}
void vtkAFAMVolumeRepresentation::SetDrawMissingValues(bool v)
{
  this->Mapper->SetDrawMissingValues(v);
}
void vtkAFAMVolumeRepresentation::SetCacheBudgetMB(double v)
{
  this->Mapper->SetCacheBudgetMB(v);
}
void vtkAFAMVolumeRepresentation::SetPrefetcher(int v)
{
  this->Mapper->SetPrefetcher(v);
}
void vtkAFAMVolumeRepresentation::SetRenderDevice(int v)
{
  this->Mapper->SetRenderDevice(v);
}
void vtkAFAMVolumeRepresentation::SetDepthCompositing(bool v)
{
  this->Mapper->SetDepthCompositing(v);
}
void vtkAFAMVolumeRepresentation::SetSampleDistance(double v)
{
  this->Mapper->SetSampleDistance(v);
}
void vtkAFAMVolumeRepresentation::SetNumberOfThreads(int v)
{
  this->Mapper->SetNumberOfThreads(v);
}
void vtkAFAMVolumeRepresentation::SetAutoAdjustImageScale(bool v)
{
  this->Mapper->SetAutoAdjustImageScale(v);
}
void vtkAFAMVolumeRepresentation::SetMinimumImageScale(double v)
{
  this->Mapper->SetMinimumImageScale(v);
}
void vtkAFAMVolumeRepresentation::SetInteractiveMissBudget(double v)
{
  this->Mapper->SetInteractiveMissBudget(v);
}
void vtkAFAMVolumeRepresentation::SetBlendMode(int v)
{
  this->Mapper->SetBlendMode(v);
}
double vtkAFAMVolumeRepresentation::GetLastImageScale()
{
  return this->Mapper->GetLastImageScale();
}
double vtkAFAMVolumeRepresentation::GetLastCachingTime()
{
  return this->Mapper->GetLastCachingTime();
}
double vtkAFAMVolumeRepresentation::GetLastRenderTime()
{
  return this->Mapper->GetLastRenderTime();
}
double vtkAFAMVolumeRepresentation::GetLastTotalTime()
{
  return this->Mapper->GetLastTotalTime();
}
vtkTypeInt64 vtkAFAMVolumeRepresentation::GetLastCacheHits()
{
  return this->Mapper->GetLastCacheHits();
}
vtkTypeInt64 vtkAFAMVolumeRepresentation::GetLastCacheMisses()
{
  return this->Mapper->GetLastCacheMisses();
}
vtkTypeInt64 vtkAFAMVolumeRepresentation::GetLastBytesRead()
{
  return this->Mapper->GetLastBytesRead();
}
vtkTypeInt64 vtkAFAMVolumeRepresentation::GetLastCacheBytes()
{
  return this->Mapper->GetLastCacheBytes();
}
vtkTypeInt64 vtkAFAMVolumeRepresentation::GetLastCulledBlocks()
{
  return this->Mapper->GetLastCulledBlocks();
}
vtkTypeInt64 vtkAFAMVolumeRepresentation::GetLastVisibleBlocks()
{
  return this->Mapper->GetLastVisibleBlocks();
}
vtkTypeInt64 vtkAFAMVolumeRepresentation::GetNumberOfFrames()
{
  return this->Mapper->GetNumberOfFrames();
}
int vtkAFAMVolumeRepresentation::GetLastUsedGpu()
{
  return this->Mapper->GetLastUsedGpu() ? 1 : 0;
}
int vtkAFAMVolumeRepresentation::GetLastImageOnDevice()
{
  return this->Mapper->GetLastImageOnDevice() ? 1 : 0;
}
const char* vtkAFAMVolumeRepresentation::GetLastInteropProblem()
{
  return this->Mapper->GetLastInteropProblem();
}
vtkTypeInt64 vtkAFAMVolumeRepresentation::GetLastDepthLimitedPixels()
{
  return this->Mapper->GetLastDepthLimitedPixels();
}
const char* vtkAFAMVolumeRepresentation::GetLastDeviceMessage()
{
  return this->Mapper->GetLastDeviceMessage();
}
vtkTypeInt64 vtkAFAMVolumeRepresentation::GetLastGpuModelsUploaded()
{
  return this->Mapper->GetLastGpuModelsUploaded();
}
vtkTypeInt64 vtkAFAMVolumeRepresentation::GetLastStandInBlocks()
{
  return this->Mapper->GetLastStandInBlocks();
}
vtkTypeInt64 vtkAFAMVolumeRepresentation::GetLastBlocksBehind()
{
  return this->Mapper->GetLastBlocksBehind();
}
vtkTypeInt64 vtkAFAMVolumeRepresentation::GetLastBytesBehind()
{
  return this->Mapper->GetLastBytesBehind();
}
vtkTypeInt64 vtkAFAMVolumeRepresentation::GetNumberOfRendererBuilds()
{
  return this->Mapper->GetNumberOfRendererBuilds();
}
const char* vtkAFAMVolumeRepresentation::GetLastSettingWarning()
{
  return this->Mapper->GetLastSettingWarning();
}

void vtkAFAMVolumeRepresentation::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << this->FileName << "\n";
  this->Mapper->PrintSelf(os, indent.GetNextIndent());
}
