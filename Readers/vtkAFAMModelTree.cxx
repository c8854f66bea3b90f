// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMModelTree.h"

#include "afam/afam_file.hpp"
#include "afam/partition.hpp"

#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkIntArray.h"
#include "vtkMultiBlockDataSet.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkStringArray.h"
#include "vtkTypeInt64Array.h"

#include <algorithm>
#include <string>

namespace
{
template <typename ArrayT, typename T>
void AddTuple(vtkFieldData* fd, const char* name, std::initializer_list<T> values)
{
  vtkNew<ArrayT> a;
  a->SetName(name);
  a->SetNumberOfComponents(static_cast<int>(values.size()));
  a->SetNumberOfTuples(1);
  int c = 0;
  for (T v : values)
  {
    a->SetTypedComponent(0, c++, v);
  }
  fd->AddArray(a);
}

void AddString(vtkFieldData* fd, const char* name, const std::string& value)
{
  vtkNew<vtkStringArray> s;
  s->SetName(name);
  s->InsertNextValue(value);
  fd->AddArray(s);
}
}

void vtkAFAMModelTree::Build(const afam::VolumeHeader& header, const afam::Partition& partition,
  const std::vector<afam::ModelEntry>& entries, const std::string& path, int piece, int numPieces,
  vtkMultiBlockDataSet* out, const std::function<void(double)>& progress)
{
  out->Initialize();
  const int levels = partition.levels();
  out->SetNumberOfBlocks(static_cast<unsigned>(levels + 1));

  // Coarsest blocks are split into numPieces contiguous linear ranges (z-major slabs).
  const int64_t coarse = partition.blockCount(0);
  numPieces = std::max(1, numPieces);
  piece = std::min(std::max(0, piece), numPieces - 1);
  const int64_t first = coarse * piece / numPieces;
  const int64_t last = coarse * (piece + 1) / numPieces;

  int64_t next = 0;
  const auto total = static_cast<double>(std::max<size_t>(1, entries.size()));
  for (int level = 0; level < levels; ++level)
  {
    vtkNew<vtkMultiBlockDataSet> levelBlock;
    const int64_t count = partition.blockCount(level);
    levelBlock->SetNumberOfBlocks(static_cast<unsigned>(count));
    out->SetBlock(static_cast<unsigned>(level), levelBlock);
    out->GetMetaData(static_cast<unsigned>(level))
      ->Set(vtkCompositeDataSet::NAME(), ("Level " + std::to_string(level)).c_str());
    for (int64_t b = 0; b < count; ++b, ++next)
    {
      const afam::Int3 ijk = partition.blockFromLinear(level, b);
      afam::Int3 root = ijk;
      for (int l = level; l > 0; --l)
      {
        root = partition.parent(l, root);
      }
      const int64_t rootIndex = partition.linearIndex(0, root);
      const std::string name = "L" + std::to_string(level) + " [" + std::to_string(ijk[0]) + "," +
        std::to_string(ijk[1]) + "," + std::to_string(ijk[2]) + "]";
      levelBlock->GetMetaData(static_cast<unsigned>(b))->Set(vtkCompositeDataSet::NAME(), name.c_str());
      if (rootIndex < first || rootIndex >= last)
      {
        continue;
      }
      const int64_t entryIndex = next;
      const afam::ModelEntry& e = entries.at(static_cast<size_t>(entryIndex));
      const afam::BlockExtent ext = partition.extent(level, ijk);

      // The leaf covers the block's voxels of the full grid; it carries no samples.
      vtkNew<vtkImageData> leaf;
      leaf->SetExtent(static_cast<int>(ext.lo[0]), static_cast<int>(ext.hi[0]),
        static_cast<int>(ext.lo[1]), static_cast<int>(ext.hi[1]), static_cast<int>(ext.lo[2]),
        static_cast<int>(ext.hi[2]));
      leaf->SetOrigin(header.origin.data());
      leaf->SetSpacing(header.spacing.data());
      vtkFieldData* fd = leaf->GetFieldData();
      AddTuple<vtkIntArray, int>(fd, LevelArray, { e.level });
      AddTuple<vtkIntArray, int>(fd, BlockArray, { e.block[0], e.block[1], e.block[2] });
      AddTuple<vtkIntArray, int>(fd, NcpArray, { e.ncp[0], e.ncp[1], e.ncp[2] });
      AddTuple<vtkIntArray, int>(fd, DegreeArray, { e.degree[0], e.degree[1], e.degree[2] });
      AddTuple<vtkDoubleArray, double>(fd, ValueRangeArray, { e.minValue, e.maxValue });
      AddTuple<vtkDoubleArray, double>(fd, RmseArray, { e.rmse });
      AddTuple<vtkDoubleArray, double>(fd, MaxErrorArray, { e.maxError });
      AddTuple<vtkTypeInt64Array, vtkTypeInt64>(fd, EntryArray, { entryIndex });
      AddTuple<vtkTypeInt64Array, vtkTypeInt64>(
        fd, PayloadBytesArray, { static_cast<vtkTypeInt64>(e.size) });
      AddString(fd, FileNameArray, path);
      levelBlock->SetBlock(static_cast<unsigned>(b), leaf);
      if (progress && (next & 255) == 0)
      {
        progress(static_cast<double>(next) / total);
      }
    }
  }
  // Last block: a 2x2x2 probe spanning the volume whose point array holds the value range, so that
  // ParaView's colour-map machinery (array list, range, transfer functions) has an array to bind
  // to; the leaves above carry no samples. Present on piece 0 only.
  if (piece == 0)
  {
    vtkNew<vtkImageData> probe;
    probe->SetDimensions(2, 2, 2);
    probe->SetOrigin(header.origin.data());
    double spacing[3];
    for (int a = 0; a < 3; ++a)
    {
      spacing[a] = header.spacing[a] * static_cast<double>(std::max<int64_t>(1, header.dims[a] - 1));
    }
    probe->SetSpacing(spacing);
    vtkNew<vtkDoubleArray> range;
    range->SetName(header.scalarName.empty() ? "scalars" : header.scalarName.c_str());
    range->SetNumberOfTuples(8);
    range->FillValue(header.valueMax);
    range->SetValue(0, header.valueMin);
    probe->GetPointData()->SetScalars(range);
    out->SetBlock(static_cast<unsigned>(levels), probe);
  }
  out->GetMetaData(static_cast<unsigned>(levels))->Set(vtkCompositeDataSet::NAME(), "Value range");

  vtkFieldData* fd = out->GetFieldData();
  AddString(fd, FileNameArray, path);
  AddTuple<vtkTypeInt64Array, vtkTypeInt64>(
    fd, DimensionsArray, { header.dims[0], header.dims[1], header.dims[2] });
  AddTuple<vtkDoubleArray, double>(fd, ValueRangeArray, { header.valueMin, header.valueMax });
  if (progress)
  {
    progress(1.0);
  }
}

std::string vtkAFAMModelTree::FileName(vtkMultiBlockDataSet* tree)
{
  if (!tree)
  {
    return {};
  }
  auto* s = vtkStringArray::SafeDownCast(tree->GetFieldData()->GetAbstractArray(FileNameArray));
  return (s && s->GetNumberOfValues() > 0) ? s->GetValue(0) : std::string();
}
