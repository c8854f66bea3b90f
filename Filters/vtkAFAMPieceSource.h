// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkAFAMPieceSource
 * @brief   A volume spread over MPI ranks, read by whole z-planes (private to the module).
 *
 * Each rank holds the samples of its piece (a sub-extent of the whole extent, split along any axes;
 * neighbouring pieces may share their boundary points) in their own sample type and exposes them in
 * an MPI window; what is read is converted to float32 by afam::samplesToFloat (static_cast, as VTK
 * converts values), so a uint8 piece costs one byte per sample, not five.
 * readSlab assembles whole planes of the global volume with passive-target one-sided reads
 * (MPI_Get of the part of each piece inside the planes), so a rank reads only the planes of the
 * rows it fits, whenever it needs them, without the owners taking part. Construction and
 * destruction are collective (MPI_Win_create / MPI_Win_free).
 */
#ifndef vtkAFAMPieceSource_h
#define vtkAFAMPieceSource_h

#include "afam/volume/volume_source.hpp"

#include "vtkMPI.h" // for MPI_Comm, MPI_Win

#include <array>
#include <mutex>
#include <string>
#include <vector>

class vtkAFAMPieceSource : public afam::VolumeSource
{
public:
  using Extent =
    std::array<int, 6>; ///< x0 x1 y0 y1 z0 z1, inclusive; empty when x1 < x0 (any axis)

  /// `pieces[r]` is rank r's extent; `samples` holds this rank's piece, x fastest, as values of
  /// `type` (the same on every rank; the array must outlive the source). Every MPI call takes
  /// `mpiLock`.
  vtkAFAMPieceSource(MPI_Comm comm,
    std::mutex& mpiLock,
    const Extent& whole,
    std::vector<Extent> pieces,
    const void* samples,
    afam::SampleType type,
    std::string name,
    std::array<double, 3> origin,
    std::array<double, 3> spacing,
    int bytesPerVoxel);
  ~vtkAFAMPieceSource() override;
  vtkAFAMPieceSource(const vtkAFAMPieceSource&) = delete;
  vtkAFAMPieceSource& operator=(const vtkAFAMPieceSource&) = delete;

  afam::Index3 dims() const override;
  std::array<double, 3> origin() const override
  {
    return this->Origin;
  }
  std::array<double, 3> spacing() const override
  {
    return this->Spacing;
  }
  std::string name() const override
  {
    return this->Name;
  }
  int bytesPerVoxel() const override
  {
    return this->BytesPerVoxel;
  }
  void readSlab(int64_t z0, int64_t zCount, float* out) override;
  /// Only the rows asked for travel (a rank fitting some lines of blocks reads their rows).
  void readRows(int64_t z0, int64_t zCount, int64_t y0, int64_t yCount, float* out) override;
  /// Under an MPI initialised below MPI_THREAD_SERIALIZED (pvbatch initialises it single-threaded),
  /// reads stay on the encoder's calling thread.
  bool readsOnCallingThread() const override
  {
    return this->CallingThreadOnly;
  }

  /// Bytes this rank has read from other ranks' pieces so far.
  uint64_t remoteBytesRead() const
  {
    return this->RemoteBytes;
  }

  static bool IsEmpty(const Extent& e)
  {
    return e[1] < e[0] || e[3] < e[2] || e[5] < e[4];
  }
  /// "" when the non-empty pieces lie inside `whole` and together cover it, else what is wrong.
  static std::string CheckCover(const Extent& whole, const std::vector<Extent>& pieces);

private:
  /// Reads the part of rank r's piece inside `region` (global extent) into `out`, which holds the
  /// box `box` (global extent); false when MPI failed.
  bool ReadPiece(int r, const Extent& region, const Extent& box, void* out);

  MPI_Comm Comm;
  MPI_Win Window;
  afam::SampleType Type; ///< type of the exposed values
  MPI_Datatype Element;  ///< the same, for MPI
  int ElementSize;
  std::vector<unsigned char> Raw; ///< a slab in the exposed type, before conversion
  std::mutex& MpiLock;
  Extent Whole;
  std::vector<Extent> Pieces;
  int Rank = 0;
  std::string Name;
  std::array<double, 3> Origin, Spacing;
  int BytesPerVoxel;
  bool CallingThreadOnly = true;
  uint64_t RemoteBytes = 0;
};

#endif
