// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAFAMModelTree.h"

#include "afam/format/afam_file.hpp"
#include "afam/format/partition.hpp"

#include "vtkArrayIteratorTemplate.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkGenericDataArray.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkIntArray.h"
#include "vtkMultiBlockDataSet.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkSmartPointer.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkStringArray.h"
#include "vtkTypeInt64Array.h"
#include "vtkVersionMacros.h"

#include <algorithm>
#include <limits>
#include <climits>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace
{
/// The scalar array of a level's leaf: one NaN ("no sample here") per point, held in no memory.
/// ParaView marks an array "(partial)" when a leaf with points lacks it (vtkPVDataSetAttributes-
/// Information::AddInformation); with it on every leaf, the "Value range" leaf alone gives the
/// array's range, and the leaves keep their extents, so that the data information (points, cells,
/// bounds: the default Scalar Opacity Unit Distance) is what it was. Its range is empty, found
/// without a pass over the points; raw access (a filter or ParaView's own Volume applied to the
/// model set) gets NaNs made on demand.
class vtkAFAMNoSamplesArray : public vtkGenericDataArray<vtkAFAMNoSamplesArray, double>
{
  using Base = vtkGenericDataArray<vtkAFAMNoSamplesArray, double>;

public:
  vtkAbstractTypeMacro(vtkAFAMNoSamplesArray, Base);
  static vtkAFAMNoSamplesArray* New();

  static double NaN()
  {
    return std::numeric_limits<double>::quiet_NaN();
  }
  double GetValue(vtkIdType) const
  {
    return NaN();
  }
  void SetValue(vtkIdType, double) {}
  void GetTypedTuple(vtkIdType, double* tuple) const
  {
    std::fill_n(tuple, this->NumberOfComponents, NaN());
  }
  void SetTypedTuple(vtkIdType, const double*) {}
  double GetTypedComponent(vtkIdType, int) const
  {
    return NaN();
  }
  void SetTypedComponent(vtkIdType, int, double) {}

  unsigned long GetActualMemorySize() const override
  {
    return static_cast<unsigned long>(this->Materialized.size() * sizeof(double) / 1024 + 1);
  }
  void* GetVoidPointer(vtkIdType valueIdx) override
  {
    this->Materialized.assign(static_cast<size_t>(this->GetNumberOfValues()), NaN());
    return this->Materialized.data() + valueIdx;
  }
  vtkArrayIterator* NewIterator() override
  {
    vtkArrayIterator* iterator = vtkArrayIteratorTemplate<double>::New();
    iterator->Initialize(this);
    return iterator;
  }

protected:
  // A new array of this kind (what filters allocate their outputs with, what DeepCopy fills) is an
  // ordinary vtkDoubleArray: it must hold the values written to it.
  vtkObjectBase* NewInstanceInternal() const override
  {
    return vtkDoubleArray::New();
  }

  vtkAFAMNoSamplesArray() = default;
  ~vtkAFAMNoSamplesArray() override = default;

  bool AllocateTuples(vtkIdType)
  {
    return true;
  }
  bool ReallocateTuples(vtkIdType)
  {
    return true;
  }

  // NaN everywhere: no range, as VTK finds for an array of NaNs, without visiting them.
  static bool NoRange(double* ranges, int components)
  {
    for (int c = 0; c < components; ++c)
    {
      ranges[2 * c] = VTK_DOUBLE_MAX;
      ranges[2 * c + 1] = VTK_DOUBLE_MIN;
    }
    return true;
  }
  bool ComputeScalarRange(double* ranges) override
  {
    return NoRange(ranges, this->NumberOfComponents);
  }
  bool ComputeVectorRange(double range[2]) override
  {
    return NoRange(range, 1);
  }
  bool ComputeFiniteScalarRange(double* ranges) override
  {
    return NoRange(ranges, this->NumberOfComponents);
  }
  bool ComputeFiniteVectorRange(double range[2]) override
  {
    return NoRange(range, 1);
  }
#if VTK_VERSION_NUMBER >= VTK_VERSION_CHECK(9, 2, 0) // the ranges that skip ghosts
  bool ComputeScalarRange(double* ranges, const unsigned char*, unsigned char) override
  {
    return NoRange(ranges, this->NumberOfComponents);
  }
  bool ComputeVectorRange(double range[2], const unsigned char*, unsigned char) override
  {
    return NoRange(range, 1);
  }
  bool ComputeFiniteScalarRange(double* ranges, const unsigned char*, unsigned char) override
  {
    return NoRange(ranges, this->NumberOfComponents);
  }
  bool ComputeFiniteVectorRange(double range[2], const unsigned char*, unsigned char) override
  {
    return NoRange(range, 1);
  }
#endif

private:
  friend Base;
  std::vector<double> Materialized; // only when raw access asks for it
  vtkAFAMNoSamplesArray(const vtkAFAMNoSamplesArray&) = delete;
  void operator=(const vtkAFAMNoSamplesArray&) = delete;
};
vtkStandardNewMacro(vtkAFAMNoSamplesArray);

template<typename ArrayT, typename T>
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

/// A field-data column of `rows` tuples of `components`, filled by value(row, component).
template<typename ArrayT, typename Fn>
void AddColumn(vtkFieldData* fd,
  const char* name,
  int components,
  const std::vector<int64_t>& rows,
  Fn value)
{
  vtkNew<ArrayT> a;
  a->SetName(name);
  a->SetNumberOfComponents(components);
  a->SetNumberOfTuples(static_cast<vtkIdType>(rows.size()));
  for (size_t r = 0; r < rows.size(); ++r)
  {
    for (int c = 0; c < components; ++c)
    {
      a->SetTypedComponent(static_cast<vtkIdType>(r), c, value(rows[r], c));
    }
  }
  fd->AddArray(a);
}

std::string ScalarName(const afam::VolumeHeader& header)
{
  return header.scalarName.empty() ? "scalars" : header.scalarName;
}

/// The leaf of one level: an image covering its models' blocks (no samples: its scalar array is
/// NaN and costs nothing) whose field data has one row per model.
vtkSmartPointer<vtkImageData> LevelLeaf(const afam::VolumeHeader& header,
  const afam::Partition& partition,
  const std::vector<afam::ModelEntry>& entries,
  const std::vector<int64_t>& rows)
{
  int extent[6] = { INT_MAX, INT_MIN, INT_MAX, INT_MIN, INT_MAX, INT_MIN };
  for (int64_t r : rows)
  {
    const afam::ModelEntry& e = entries[static_cast<size_t>(r)];
    const afam::BlockExtent ext = partition.extent(e.level, e.block);
    for (int a = 0; a < 3; ++a)
    {
      extent[2 * a] = std::min(extent[2 * a], static_cast<int>(ext.lo[a]));
      extent[2 * a + 1] = std::max(extent[2 * a + 1], static_cast<int>(ext.hi[a]));
    }
  }
  auto leaf = vtkSmartPointer<vtkImageData>::New();
  leaf->SetExtent(extent);
  leaf->SetOrigin(header.origin.data());
  leaf->SetSpacing(header.spacing.data());
  vtkNew<vtkAFAMNoSamplesArray> scalars;
  scalars->SetName(ScalarName(header).c_str());
  scalars->SetNumberOfTuples(leaf->GetNumberOfPoints());
  leaf->GetPointData()->SetScalars(scalars);
  vtkFieldData* fd = leaf->GetFieldData();
  auto entry = [&](int64_t r) -> const afam::ModelEntry&
  { return entries[static_cast<size_t>(r)]; };
  AddColumn<vtkIntArray>(
    fd, vtkAFAMModelTree::LevelArray, 1, rows, [&](int64_t r, int) { return entry(r).level; });
  AddColumn<vtkIntArray>(
    fd, vtkAFAMModelTree::BlockArray, 3, rows, [&](int64_t r, int c) { return entry(r).block[c]; });
  AddColumn<vtkIntArray>(
    fd, vtkAFAMModelTree::NcpArray, 3, rows, [&](int64_t r, int c) { return entry(r).ncp[c]; });
  AddColumn<vtkIntArray>(fd,
    vtkAFAMModelTree::DegreeArray,
    3,
    rows,
    [&](int64_t r, int c) { return entry(r).degree[c]; });
  AddColumn<vtkDoubleArray>(fd,
    vtkAFAMModelTree::ValueRangeArray,
    2,
    rows,
    [&](int64_t r, int c) { return c == 0 ? entry(r).minValue : entry(r).maxValue; });
  AddColumn<vtkDoubleArray>(
    fd, vtkAFAMModelTree::RmseArray, 1, rows, [&](int64_t r, int) { return entry(r).rmse; });
  AddColumn<vtkDoubleArray>(fd,
    vtkAFAMModelTree::MaxErrorArray,
    1,
    rows,
    [&](int64_t r, int) { return entry(r).maxError; });
  AddColumn<vtkTypeInt64Array>(
    fd, vtkAFAMModelTree::EntryArray, 1, rows, [](int64_t r, int) { return r; });
  AddColumn<vtkTypeInt64Array>(fd,
    vtkAFAMModelTree::PayloadBytesArray,
    1,
    rows,
    [&](int64_t r, int) { return static_cast<vtkTypeInt64>(entry(r).size); });
  AddColumn<vtkTypeInt64Array>(fd,
    vtkAFAMModelTree::StoredBytesArray,
    1,
    rows,
    [&](int64_t r, int) { return static_cast<vtkTypeInt64>(entry(r).storedSize); });
  return leaf;
}
}

void vtkAFAMModelTree::Build(const afam::VolumeHeader& header,
  const afam::Partition& partition,
  const std::vector<afam::ModelEntry>& entries,
  const std::string& path,
  int piece,
  int numPieces,
  vtkMultiBlockDataSet* out,
  const std::function<void(double)>& progress,
  long long step)
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
  for (int level = 0; level < levels; ++level)
  {
    const int64_t count = partition.blockCount(level);
    std::vector<int64_t> rows; // the level's models in this piece, as entry indices
    for (int64_t b = 0; b < count; ++b, ++next)
    {
      afam::Int3 root = partition.blockFromLinear(level, b);
      for (int l = level; l > 0; --l)
      {
        root = partition.parent(l, root);
      }
      const int64_t rootIndex = partition.linearIndex(0, root);
      if (rootIndex >= first && rootIndex < last)
      {
        rows.push_back(next);
      }
    }
    if (next > static_cast<int64_t>(entries.size()))
    {
      throw std::runtime_error("the index has fewer entries than the partition has blocks");
    }
    if (!rows.empty())
    {
      out->SetBlock(static_cast<unsigned>(level), LevelLeaf(header, partition, entries, rows));
    }
    out->GetMetaData(static_cast<unsigned>(level))
      ->Set(vtkCompositeDataSet::NAME(), ("Level " + std::to_string(level)).c_str());
    if (progress)
    {
      progress(static_cast<double>(level + 1) / static_cast<double>(levels));
    }
  }
  // Last block: a 2x2x2 probe spanning the volume whose point array holds the value range, so that
  // ParaView's colour-map machinery (array list, range, transfer functions) has an array to bind
  // to; the leaves above carry no samples (their array of that name is NaN and holds no memory,
  // so that the array is on every leaf: not "(partial)"). Present on piece 0 only.
  if (piece == 0)
  {
    vtkNew<vtkImageData> probe;
    probe->SetDimensions(2, 2, 2);
    probe->SetOrigin(header.origin.data());
    double spacing[3];
    for (int a = 0; a < 3; ++a)
    {
      spacing[a] =
        header.spacing[a] * static_cast<double>(std::max<int64_t>(1, header.dims[a] - 1));
    }
    probe->SetSpacing(spacing);
    vtkNew<vtkDoubleArray> range;
    range->SetName(ScalarName(header).c_str());
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
  AddTuple<vtkTypeInt64Array, vtkTypeInt64>(fd, StepArray, { static_cast<vtkTypeInt64>(step) });
  AddString(fd, BoundKindArray, afam::boundKindName(header.boundKind));
  AddTuple<vtkDoubleArray, double>(fd, BoundArray, { afam::absoluteBound(header) });
  // What marked the source's missing samples (the decoded samples are NaN there whatever did).
  AddString(fd, MissingKindArray, afam::missingKindName(header.missing));
  AddTuple<vtkDoubleArray, double>(fd,
    MissingValueArray,
    { header.missing == afam::MissingKind::Value ? header.missingValue
                                                 : std::numeric_limits<double>::quiet_NaN() });
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

long long vtkAFAMModelTree::Step(vtkMultiBlockDataSet* tree)
{
  if (!tree)
  {
    return 0;
  }
  auto* a = vtkTypeInt64Array::SafeDownCast(tree->GetFieldData()->GetAbstractArray(StepArray));
  return (a && a->GetNumberOfTuples() > 0) ? static_cast<long long>(a->GetValue(0)) : 0;
}

long long vtkAFAMModelTree::StepAtTime(const std::vector<double>& times, vtkInformation* info)
{
  if (times.size() < 2 || !info->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP()))
  {
    return 0;
  }
  const double t = info->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP());
  const auto after = std::upper_bound(times.begin(), times.end(), t + 1e-12 * std::abs(t));
  return after == times.begin() ? 0 : static_cast<long long>(after - times.begin()) - 1;
}
