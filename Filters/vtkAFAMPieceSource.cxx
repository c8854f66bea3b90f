// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMPieceSource.h"

#include "afam/base/errors.hpp"

#include <algorithm>
#include <set>
#include <sstream>

namespace
{
using Extent = vtkAFAMPieceSource::Extent;

Extent Intersect(const Extent& a, const Extent& b)
{
  Extent c;
  for (int i = 0; i < 3; ++i)
  {
    c[2 * i] = std::max(a[2 * i], b[2 * i]);
    c[2 * i + 1] = std::min(a[2 * i + 1], b[2 * i + 1]);
  }
  return c;
}

int Points(const Extent& e, int axis)
{
  return e[2 * axis + 1] - e[2 * axis] + 1;
}

std::string Text(const Extent& e)
{
  std::ostringstream s;
  s << "[" << e[0] << ".." << e[1] << ", " << e[2] << ".." << e[3] << ", " << e[4] << ".." << e[5]
    << "]";
  return s.str();
}

/// The MPI type of a sample type.
MPI_Datatype MpiType(afam::SampleType type)
{
  switch (type)
  {
    case afam::SampleType::Int8:
      return MPI_INT8_T;
    case afam::SampleType::UInt8:
      return MPI_UINT8_T;
    case afam::SampleType::Int16:
      return MPI_INT16_T;
    case afam::SampleType::UInt16:
      return MPI_UINT16_T;
    case afam::SampleType::Int32:
      return MPI_INT32_T;
    case afam::SampleType::UInt32:
      return MPI_UINT32_T;
    case afam::SampleType::Int64:
      return MPI_INT64_T;
    case afam::SampleType::UInt64:
      return MPI_UINT64_T;
    case afam::SampleType::Float32:
      return MPI_FLOAT;
    case afam::SampleType::Float64:
      return MPI_DOUBLE;
  }
  return MPI_DATATYPE_NULL;
}

/// An MPI subarray type (x fastest) of `sub` points starting at `start` in a box of `box` points.
MPI_Datatype Subarray(MPI_Datatype element, const int box[3], const int sub[3], const int start[3])
{
  MPI_Datatype type;
  MPI_Type_create_subarray(3, box, sub, start, MPI_ORDER_FORTRAN, element, &type);
  MPI_Type_commit(&type);
  return type;
}

/// The points of `whole` (grid of the pieces' boundaries) that no piece covers: the first found.
bool FindUncovered(const Extent& whole,
  const std::vector<Extent>& pieces,
  std::array<int, 3>& where)
{
  std::array<std::vector<int>, 3> cuts; // the first point of each interval between boundaries
  for (int a = 0; a < 3; ++a)
  {
    std::set<int> c{ whole[2 * a] };
    for (const Extent& p : pieces)
    {
      for (int v : { p[2 * a], p[2 * a + 1] + 1 })
      {
        if (v > whole[2 * a] && v <= whole[2 * a + 1])
        {
          c.insert(v);
        }
      }
    }
    cuts[a].assign(c.begin(), c.end());
  }
  for (int z : cuts[2])
    for (int y : cuts[1])
      for (int x : cuts[0])
      {
        const bool covered = std::any_of(pieces.begin(),
          pieces.end(),
          [&](const Extent& p)
          { return x >= p[0] && x <= p[1] && y >= p[2] && y <= p[3] && z >= p[4] && z <= p[5]; });
        if (!covered)
        {
          where = { x, y, z };
          return true;
        }
      }
  return false;
}
} // namespace

std::string vtkAFAMPieceSource::CheckCover(const Extent& whole, const std::vector<Extent>& pieces)
{
  if (IsEmpty(whole))
  {
    return "the whole extent " + Text(whole) + " is empty";
  }
  std::vector<Extent> nonEmpty;
  for (size_t r = 0; r < pieces.size(); ++r)
  {
    if (IsEmpty(pieces[r]))
    {
      continue;
    }
    if (Intersect(pieces[r], whole) != pieces[r])
    {
      return "rank " + std::to_string(r) + "'s piece " + Text(pieces[r]) +
        " reaches outside the whole extent " + Text(whole);
    }
    nonEmpty.push_back(pieces[r]);
  }
  std::array<int, 3> p{};
  if (nonEmpty.size() > 4096) // the boundary grid grows as ranks^3: trust a pipeline that large
  {
    return std::string();
  }
  if (FindUncovered(whole, nonEmpty, p))
  {
    return "no rank holds point (" + std::to_string(p[0]) + ", " + std::to_string(p[1]) + ", " +
      std::to_string(p[2]) + ") of the whole extent " + Text(whole);
  }
  return std::string();
}

vtkAFAMPieceSource::vtkAFAMPieceSource(MPI_Comm comm,
  std::mutex& mpiLock,
  const Extent& whole,
  std::vector<Extent> pieces,
  const void* samples,
  afam::SampleType type,
  std::string name,
  std::array<double, 3> origin,
  std::array<double, 3> spacing,
  int bytesPerVoxel)
  : Comm(comm)
  , Type(type)
  , Element(MpiType(type))
  , ElementSize(afam::sampleTypeSize(type))
  , MpiLock(mpiLock)
  , Whole(whole)
  , Pieces(std::move(pieces))
  , Name(std::move(name))
  , Origin(origin)
  , Spacing(spacing)
  , BytesPerVoxel(bytesPerVoxel)
{
  std::lock_guard<std::mutex> lock(this->MpiLock);
  MPI_Comm_rank(comm, &this->Rank);
  int threadLevel = MPI_THREAD_SINGLE;
  MPI_Query_thread(&threadLevel);
  this->CallingThreadOnly = threadLevel < MPI_THREAD_SERIALIZED;
  const Extent& mine = this->Pieces[static_cast<size_t>(this->Rank)];
  const MPI_Aint bytes = IsEmpty(mine) ? 0
                                       : static_cast<MPI_Aint>(this->ElementSize) *
      Points(mine, 0) * Points(mine, 1) * Points(mine, 2);
  static double nothing = 0;
  MPI_Win_create(const_cast<void*>(bytes ? samples : &nothing),
    bytes,
    this->ElementSize,
    MPI_INFO_NULL,
    comm,
    &this->Window);
}

vtkAFAMPieceSource::~vtkAFAMPieceSource()
{
  std::lock_guard<std::mutex> lock(this->MpiLock);
  MPI_Win_free(&this->Window);
}

afam::Index3 vtkAFAMPieceSource::dims() const
{
  return { Points(this->Whole, 0), Points(this->Whole, 1), Points(this->Whole, 2) };
}

bool vtkAFAMPieceSource::ReadPiece(int r, const Extent& region, const Extent& box, void* out)
{
  const Extent& piece = this->Pieces[static_cast<size_t>(r)];
  const int pieceBox[3] = { Points(piece, 0), Points(piece, 1), Points(piece, 2) };
  const int outBox[3] = { Points(box, 0), Points(box, 1), Points(box, 2) };
  const int sub[3] = { Points(region, 0), Points(region, 1), Points(region, 2) };
  const int inPiece[3] = { region[0] - piece[0], region[2] - piece[2], region[4] - piece[4] };
  const int inOut[3] = { region[0] - box[0], region[2] - box[2], region[4] - box[4] };
  MPI_Datatype target = Subarray(this->Element, pieceBox, sub, inPiece);
  MPI_Datatype origin = Subarray(this->Element, outBox, sub, inOut);
  const int rc = MPI_Get(out, 1, origin, r, 0, 1, target, this->Window);
  MPI_Type_free(&origin);
  MPI_Type_free(&target);
  if (r != this->Rank)
  {
    this->RemoteBytes +=
      static_cast<uint64_t>(this->ElementSize) * static_cast<uint64_t>(sub[0]) * sub[1] * sub[2];
  }
  return rc == MPI_SUCCESS;
}

void vtkAFAMPieceSource::readSlab(int64_t z0, int64_t zCount, float* out)
{
  this->readRows(z0, zCount, 0, Points(this->Whole, 1), out);
}

void vtkAFAMPieceSource::readRows(int64_t z0,
  int64_t zCount,
  int64_t y0,
  int64_t yCount,
  float* out)
{
  Extent wanted = this->Whole;
  wanted[2] = this->Whole[2] + static_cast<int>(y0);
  wanted[3] = wanted[2] + static_cast<int>(yCount) - 1;
  wanted[4] = this->Whole[4] + static_cast<int>(z0);
  wanted[5] = wanted[4] + static_cast<int>(zCount) - 1;
  const size_t count = static_cast<size_t>(Points(wanted, 0)) *
    static_cast<size_t>(Points(wanted, 1)) * static_cast<size_t>(zCount);
  const bool direct = this->Type == afam::SampleType::Float32;
  if (!direct)
  {
    this->Raw.resize(count * static_cast<size_t>(this->ElementSize));
  }
  void* into = direct ? static_cast<void*>(out) : static_cast<void*>(this->Raw.data());
  std::lock_guard<std::mutex> lock(this->MpiLock);
  MPI_Win_lock_all(0, this->Window);
  const Extent& mine = this->Pieces[static_cast<size_t>(this->Rank)];
  int failed = -1;
  if (!IsEmpty(mine) && Intersect(mine, wanted) == wanted) // all here: no other rank is asked
  {
    failed = this->ReadPiece(this->Rank, wanted, wanted, into) ? -1 : this->Rank;
  }
  else
  {
    for (size_t r = 0; r < this->Pieces.size() && failed < 0; ++r)
    {
      const Extent region = Intersect(this->Pieces[r], wanted);
      if (!IsEmpty(this->Pieces[r]) && !IsEmpty(region) &&
        !this->ReadPiece(static_cast<int>(r), region, wanted, into))
      {
        failed = static_cast<int>(r);
      }
    }
  }
  MPI_Win_unlock_all(this->Window);
  if (failed >= 0)
  {
    throw afam::IoError("reading planes " + std::to_string(z0) + ".." +
      std::to_string(z0 + zCount - 1) + " from the piece of rank " + std::to_string(failed) +
      " failed (MPI_Get)");
  }
  if (!direct)
  {
    afam::samplesToFloat(this->Type, this->Raw.data(), count, out);
  }
}
