// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
// Private helper shared by vtkAFAMReader and vtkAFAMEncoder (not wrapped, not installed): builds
// the metadata multiblock of a set of micro-models from Core's index structures: one leaf per
// level, whose field data holds one row per model (a leaf per model would cost kilobytes of VTK
// objects per model, and ParaView's data information more, on every update). It reads no payload.
#ifndef vtkAFAMModelTree_h
#define vtkAFAMModelTree_h

#include <functional>
#include <string>
#include <vector>

class vtkInformation;
class vtkMultiBlockDataSet;
namespace afam
{
struct VolumeHeader;
struct ModelEntry;
class Partition;
}

namespace vtkAFAMModelTree
{
/// Field-data array names on the level leaves (one tuple per model) and on the root.
constexpr const char* FileNameArray = "AFAM_FileName";         // root: the .afam path
constexpr const char* LevelArray = "AFAM_Level";               // leaves: 0 = coarsest
constexpr const char* BlockArray = "AFAM_Block";               // leaves: block i, j, k
constexpr const char* NcpArray = "AFAM_NCP";                   // leaves: control points per axis
constexpr const char* DegreeArray = "AFAM_Degree";             // leaves: effective degree per axis
constexpr const char* ValueRangeArray = "AFAM_ValueRange";     // leaves: model min, max
constexpr const char* RmseArray = "AFAM_RMSE";                 // leaves: achieved RMSE
constexpr const char* MaxErrorArray = "AFAM_MaxError";         // leaves: achieved max abs error
constexpr const char* EntryArray = "AFAM_EntryIndex";          // leaves: index entry in the file
constexpr const char* PayloadBytesArray = "AFAM_PayloadBytes"; // leaves: decoded control points
constexpr const char* StoredBytesArray = "AFAM_StoredBytes";   // leaves: bytes in the file
constexpr const char* DimensionsArray = "AFAM_Dimensions";     // root: volume samples per axis
constexpr const char* StepArray = "AFAM_Step";                 // root: time step of a run
constexpr const char* BoundKindArray = "AFAM_BoundKind";       // root: "rmse" or "max_error"
constexpr const char* BoundArray = "AFAM_Bound";               // root: the bound, data units
constexpr const char* MissingKindArray = "AFAM_MissingKind";   // root: "none", "nan" or "value"
constexpr const char* MissingValueArray = "AFAM_MissingValue"; // root: the fill value (NaN if none)

/// Fills `out`: blocks 0..levels-1 are the levels, block `levels` the "Value range" probe. A
/// level's leaf is a vtkImageData spanning its models' blocks (no samples: its point array of the
/// scalar's name is NaN and holds no memory) whose field-data arrays
/// hold one tuple per model, in file order. Piece `piece` of `numPieces` keeps the models whose
/// coarsest-level ancestor lies in its contiguous range of coarsest blocks (z-major slabs:
/// spatially coherent); a level with none of them is a null block, so every rank has the same
/// structure. `progress` gets fractions in [0, 1].
void Build(const afam::VolumeHeader& header,
  const afam::Partition& partition,
  const std::vector<afam::ModelEntry>& entries,
  const std::string& path,
  int piece,
  int numPieces,
  vtkMultiBlockDataSet* out,
  const std::function<void(double)>& progress,
  long long step = 0);

/// The .afam path stored in a multiblock built by Build (empty when there is none).
std::string FileName(vtkMultiBlockDataSet* tree);
/// The time step of the run the tree describes (0 for a file of one step, or no tree).
long long Step(vtkMultiBlockDataSet* tree);
/// The step a pipeline's UPDATE_TIME_STEP in `info` asks for among `times`: the last whose time
/// is not after it (the first before every step), as ParaView's file series do; 0 for fewer
/// than two steps or no time asked.
long long StepAtTime(const std::vector<double>& times, vtkInformation* info);
}

#endif
