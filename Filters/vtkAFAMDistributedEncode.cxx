// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMDistributedEncode.h"

#include "vtkDataArray.h"
#include "vtkImageData.h"
#include "vtkMultiProcessController.h"
#include "vtkSetGet.h" // vtkTemplateMacro

#ifdef AFAM_HAVE_MPI
#include "vtkAFAMControllerTeam.h"
#include "vtkAFAMPieceSource.h"
#include "vtkMPICommunicator.h"

#include "afam/volume/missing_value_source.hpp"
#include "afam/volume/valid_mask_source.hpp"
#endif

#include <sstream>

std::string vtkAFAMRefusedType(vtkAbstractArray* array)
{
  return "array '" + std::string(array->GetName() ? array->GetName() : "") + "' holds " +
    array->GetDataTypeAsString() + " values (" + array->GetClassName() +
    "), which the encoder cannot take: it takes one-component arrays of " +
    afam::sampleTypeNames() + " values";
}

bool vtkAFAMSampleTypeOf(int vtkType, afam::SampleType& type)
{
  switch (vtkType)
  {
    vtkTemplateMacro(type = afam::sampleTypeOf<VTK_TT>(); return true);
  }
  return false;
}

bool vtkAFAMGetSamples(vtkDataArray* array, vtkAFAMArraySamples& samples, std::string& error)
{
  if (!vtkAFAMSampleTypeOf(array->GetDataType(), samples.Type))
  {
    error = vtkAFAMRefusedType(array);
    return false;
  }
  samples.Copy = nullptr;
  if (!array->HasStandardMemoryLayout())
  {
    samples.Copy =
      vtkSmartPointer<vtkDataArray>::Take(vtkDataArray::CreateDataArray(array->GetDataType()));
    samples.Copy->DeepCopy(array);
  }
  samples.Data = (samples.Copy ? samples.Copy.Get() : array)->GetVoidPointer(0);
  return true;
}

#ifdef AFAM_HAVE_MPI

bool vtkAFAMCanEncodePieces()
{
  return true;
}

namespace
{
using Extent = vtkAFAMPieceSource::Extent;

/// Throws on every rank when any rank's `error` is not empty.
void Agree(vtkAFAMControllerTeam& team, const std::string& error)
{
  const std::string agreed = team.agreeOnError(error);
  if (!agreed.empty())
  {
    throw afam::Error("encode: " + agreed);
  }
}

/// What is wrong with this rank's piece and array ("" when nothing is); `samples` gets the array's.
std::string CheckPiece(vtkImageData* piece,
  vtkDataArray* array,
  const std::string& arrayError,
  vtkAFAMArraySamples& samples)
{
  if (!arrayError.empty())
  {
    return arrayError;
  }
  const vtkIdType points = piece->GetNumberOfPoints();
  if (array->GetNumberOfTuples() != points)
  {
    std::ostringstream msg;
    msg << "array '" << (array->GetName() ? array->GetName() : "") << "' has "
        << array->GetNumberOfTuples() << " values for the " << points << " points of this piece";
    return msg.str();
  }
  std::string error;
  vtkAFAMGetSamples(array, samples, error);
  return error;
}

/// Origin and spacing of rank `first` (whose piece is not empty), on every rank: the file's origin
/// is the world position of the whole extent's first point.
void AgreeOnGeometry(vtkAFAMControllerTeam& team,
  vtkImageData* piece,
  int first,
  const int whole[6],
  std::array<double, 3>& origin,
  std::array<double, 3>& spacing)
{
  std::ostringstream text;
  text.precision(17);
  const double* o = piece->GetOrigin();
  const double* s = piece->GetSpacing();
  text << o[0] << " " << o[1] << " " << o[2] << " " << s[0] << " " << s[1] << " " << s[2];
  std::istringstream agreed(team.broadcast(text.str(), first));
  agreed >> origin[0] >> origin[1] >> origin[2] >> spacing[0] >> spacing[1] >> spacing[2];
  for (int a = 0; a < 3; ++a)
  {
    origin[a] += static_cast<double>(whole[2 * a]) * spacing[a];
  }
}
} // namespace

vtkAFAMPiecesEncoded vtkAFAMEncodePieces(vtkMultiProcessController* controller,
  vtkImageData* piece,
  vtkDataArray* array,
  const std::string& arrayError,
  const int wholeExtent[6],
  const vtkAFAMPieceMarks& marks,
  const vtkAFAMTeamEncode& encode)
{
  vtkAFAMControllerTeam team(controller);
  auto* communicator = vtkMPICommunicator::SafeDownCast(controller->GetCommunicator());
  Extent mine{ 0, -1, 0, -1, 0, -1 };
  if (piece && piece->GetNumberOfPoints() > 0)
  {
    piece->GetExtent(mine.data());
  }
  const bool empty = vtkAFAMPieceSource::IsEmpty(mine);
  vtkAFAMArraySamples samples;
  Agree(team,
    !communicator ? "the ranks are not connected by MPI (vtkMPICommunicator)"
      : empty     ? std::string()
                  : CheckPiece(piece, array, arrayError, samples));

  const Extent whole{
    wholeExtent[0], wholeExtent[1], wholeExtent[2], wholeExtent[3], wholeExtent[4], wholeExtent[5]
  };
  const int first = team.reduceMin(empty ? team.size() : team.rank());
  if (first == team.size())
  {
    throw afam::Error("encode: every rank's piece of the whole extent [" +
      std::to_string(whole[0]) + ".." + std::to_string(whole[1]) + ", " + std::to_string(whole[2]) +
      ".." + std::to_string(whole[3]) + ", " + std::to_string(whole[4]) + ".." +
      std::to_string(whole[5]) + "] is empty: nothing to encode");
  }
  const std::string mineName = empty || !array->GetName() ? "scalars" : array->GetName();
  const std::string name = team.broadcast(mineName, first);
  const int bytes =
    std::stoi(team.broadcast(empty ? "4" : std::to_string(array->GetDataTypeSize()), first));
  Agree(team,
    empty || mineName == name ? std::string()
                              : "this piece's array is '" + mineName + "', rank " +
        std::to_string(first) + "'s is '" + name + "': every rank must encode the same array");
  std::array<double, 3> origin{}, spacing{};
  AgreeOnGeometry(team, piece, first, wholeExtent, origin, spacing);

  // Extents and sample types of every piece (-1: an empty piece).
  const bool masked = !empty && marks.Valid; // shared as float32 with NaN where it is 0
  const int mineType =
    empty ? -1 : static_cast<int>(masked ? afam::SampleType::Float32 : samples.Type);
  const int info[7] = { mine[0], mine[1], mine[2], mine[3], mine[4], mine[5], mineType };
  const std::vector<int> all = team.allGather(info, 7);
  std::vector<Extent> pieces(static_cast<size_t>(team.size()));
  int type = -1;
  for (size_t r = 0; r < pieces.size(); ++r)
  {
    std::copy(&all[7 * r], &all[7 * r + 6], pieces[r].begin());
    const int other = all[7 * r + 6];
    type = other < 0              ? type
      : type < 0 || type == other ? other
                                  : static_cast<int>(afam::SampleType::Float32);
  }
  Agree(team, team.rank() == 0 ? vtkAFAMPieceSource::CheckCover(whole, pieces) : std::string());

  // The values as they are where every piece has the same type, else this piece as float32.
  const auto exposed = static_cast<afam::SampleType>(type);
  std::vector<float> converted;
  if (!empty && (masked || exposed != samples.Type))
  {
    converted.resize(static_cast<size_t>(array->GetNumberOfTuples()));
    afam::samplesToFloat(samples.Type, samples.Data, converted.size(), converted.data());
    if (masked)
    {
      afam::markInvalid(marks.Valid, static_cast<int64_t>(converted.size()), converted.data());
    }
  }
  const void* values = empty ? nullptr : converted.empty() ? samples.Data : converted.data();
  vtkAFAMPieceSource source(*communicator->GetMPIComm()->GetHandle(),
    team.Lock(),
    whole,
    std::move(pieces),
    values,
    exposed,
    name,
    origin,
    spacing,
    bytes);
  vtkAFAMPiecesEncoded result;
  result.arrayName = name;
  if (!marks.UseValue)
  {
    result.stats = encode(source, team);
  }
  else
  {
    afam::MissingValueSource filled(source, marks.Value, exposed);
    result.stats = encode(filled, team);
    std::vector<uint8_t> found{ static_cast<uint8_t>(filled.matches() > 0 ? 1 : 0) };
    team.mergeFlags(found); // each rank read its share of the samples
    result.missingValueFound = found[0] != 0;
  }
  std::copy(mine.begin(), mine.end(), result.pieceExtent);
  result.remoteBytesRead = source.remoteBytesRead();
  return result;
}

#else

bool vtkAFAMCanEncodePieces()
{
  return false;
}

vtkAFAMPiecesEncoded vtkAFAMEncodePieces(vtkMultiProcessController*,
  vtkImageData*,
  vtkDataArray*,
  const std::string&,
  const int*,
  const vtkAFAMPieceMarks&,
  const vtkAFAMTeamEncode&)
{
  throw afam::Error("encode: this build of the plugin has no MPI (VTK::ParallelMPI): encoding "
                    "runs on one process");
}

#endif
