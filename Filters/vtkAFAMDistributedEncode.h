// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
/**
 * @brief   Encoding an image spread over MPI ranks (private to the module; vtkAFAMEncoder).
 *
 * Every rank of the controller calls vtkAFAMEncodePieces with its piece of the image. The ranks
 * agree on the array and the geometry, share the pieces' extents, expose their pieces to one
 * another (vtkAFAMPieceSource) and run Core's encoder as one team (vtkAFAMControllerTeam): each
 * fits a share of every level's rows of blocks, and rank 0 alone writes the file (one volume, or
 * a run's next step). The models are
 * those of a one-process encode of the whole image. Any error, on any rank, is thrown on every
 * rank.
 */
#ifndef vtkAFAMDistributedEncode_h
#define vtkAFAMDistributedEncode_h

#include "afam/encode/encoder.hpp"
#include "afam/volume/sample_type.hpp"

#include "vtkDataArray.h"
#include "vtkSmartPointer.h"

#include <cstdint>
#include <functional>
#include <string>

class vtkAbstractArray;
class vtkImageData;
class vtkMultiProcessController;

/// A point array's values as the encoder reads them: in their own type, converted to float only
/// as planes are read (afam::samplesToFloat, VTK's static_cast), never copied to float whole.
struct vtkAFAMArraySamples
{
  const void* Data = nullptr; ///< the array's values, x fastest
  afam::SampleType Type = afam::SampleType::Float32;
  /// The same values in VTK's standard layout, where the array keeps them in another (an
  /// implicit or structure-of-arrays array): a copy in their own type.
  vtkSmartPointer<vtkDataArray> Copy;
};

/// The sample type of VTK scalar type `vtkType`; false for one afam::SampleType does not name
/// (bits, strings, ...).
bool vtkAFAMSampleTypeOf(int vtkType, afam::SampleType& type);

/// The samples of a one-component `array`; false, with `error` naming the array and its type,
/// for a type the encoder cannot take (vtkAFAMSampleTypeOf).
bool vtkAFAMGetSamples(vtkDataArray* array, vtkAFAMArraySamples& samples, std::string& error);

/// "array 'NAME' holds TYPE values (CLASS), which the encoder cannot take: ..." for an array of a
/// type vtkAFAMGetSamples refuses, or of no numbers at all (strings, variants).
std::string vtkAFAMRefusedType(vtkAbstractArray* array);

/// What marks a piece's missing samples besides NaN (checked beforehand: vtkAFAMMissingSamples.h).
struct vtkAFAMPieceMarks
{
  const uint8_t* Valid = nullptr; ///< the piece's valid-point mask (0: missing), or none
  bool UseValue = false;          ///< the samples equal to Value are missing
  double Value = 0;
};

/// What one rank did in a distributed encode.
struct vtkAFAMPiecesEncoded
{
  afam::EncodeStats stats; ///< the whole volume's on rank 0 (encodeVolume with a team)
  int pieceExtent[6] = { 0, -1, 0, -1, 0, -1 }; ///< this rank's piece (empty: x1 < x0)
  uint64_t remoteBytesRead = 0;                 ///< samples read from other ranks' pieces, in bytes
  bool missingValueFound = false; ///< with marks.UseValue: some rank's sample equalled it
  std::string arrayName;          ///< the array the ranks encoded
};

/// What the ranks do with the volume their pieces make up, together (collective): e.g. encode it
/// into one file (afam::encodeVolume with the team) or as the next step of a run
/// (afam::RunEncoder::addStep with the team).
using vtkAFAMTeamEncode =
  std::function<afam::EncodeStats(afam::VolumeSource& volume, afam::EncodeTeam& team)>;

/// `array` is the chosen point array of `piece` (nullptr when `arrayError` says why none could be
/// chosen; both unused where the piece is empty); `wholeExtent` is the pipeline's whole extent.
/// A piece with a valid-point mask (`marks`) is shared as float32 with NaN where the mask is 0;
/// a fill value marks the samples of the whole volume as they are read.
/// Throws std::exception (afam::Error or afam::Cancelled) with the same message on every rank.
vtkAFAMPiecesEncoded vtkAFAMEncodePieces(vtkMultiProcessController* controller,
  vtkImageData* piece,
  vtkDataArray* array,
  const std::string& arrayError,
  const int wholeExtent[6],
  const vtkAFAMPieceMarks& marks,
  const vtkAFAMTeamEncode& encode);

/// Whether this build can encode across ranks (the module was built with VTK::ParallelMPI).
bool vtkAFAMCanEncodePieces();

#endif
