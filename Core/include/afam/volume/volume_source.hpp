// SPDX-License-Identifier: BSD-3-Clause
// Where the encoder's samples come from: a scalar volume read by whole z-planes, converted to
// float32 as they are read. Sources: a caller's array of any SampleType, a headerless raw file, the
// Marschner-Lobb function.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "afam/format/partition.hpp"
#include "afam/volume/sample_type.hpp"

namespace afam {

/// A scalar volume read by whole z-planes. Implementations: ArraySource, RawFileSource,
/// MarschnerLobbSource. readSlab and readRows are called from one thread at a time, unless the
/// source says concurrentReads().
class VolumeSource {
 public:
  virtual ~VolumeSource() = default;
  virtual Index3 dims() const = 0;
  virtual std::array<double, 3> origin() const { return {0, 0, 0}; }
  virtual std::array<double, 3> spacing() const { return {1, 1, 1}; }
  virtual std::string name() const { return "scalars"; }
  /// dims[0] * dims[1] * zCount floats, x fastest, planes z0 .. z0+zCount-1.
  virtual void readSlab(int64_t z0, int64_t zCount, float* out) = 0;
  /// Rows y0 .. y0+yCount-1 of the same planes: dims[0] * yCount * zCount floats. The default
  /// reads whole planes (readSlab) and keeps the rows; a source that can read fewer overrides it.
  virtual void readRows(int64_t z0, int64_t zCount, int64_t y0, int64_t yCount, float* out);
  /// The type in which readStoredRows gives the samples as stored, where the source can and the
  /// float readRows gives for a sample is float(stored sample) (a plain conversion: no byte swap,
  /// no missing value, no scaling); none (the default) where not. The encoder then reads 1- or
  /// 2-byte samples without making floats of them first.
  virtual std::optional<SampleType> storedType() const { return std::nullopt; }
  /// readRows' samples as stored (storedType()): dims[0] * yCount * zCount of them. The default
  /// throws: only a source with a storedType() has them.
  virtual void readStoredRows(int64_t z0, int64_t zCount, int64_t y0, int64_t yCount, void* out);
  /// If the source knows its value range without a pass over the data, it says so here; else
  /// the encoder computes it (and checks for NaN/Inf) in one streaming pass.
  virtual bool knownRange(double& lo, double& hi) const {
    (void)lo;
    (void)hi;
    return false;
  }
  /// With knownRange: whether some sample is NaN (missing), which the encoder then does not learn
  /// from a pass of its own.
  virtual bool knownMissing() const { return false; }
  /// Bytes per voxel of the original data (for the compression ratio).
  virtual int bytesPerVoxel() const { return 4; }
  /// true when readSlab may only run on the thread that called the encoder (e.g. it reads through
  /// an MPI library initialised without thread support); the encoder then samples a batch and fits
  /// it in turn, instead of sampling the next batch on a thread of its own meanwhile.
  virtual bool readsOnCallingThread() const { return false; }
  /// true when readSlab and readRows may run on several threads at once, for disjoint planes
  /// (the encoder then reads a chunk's planes in parallel: PlaneReader). A source with state of
  /// its own (a stream, a shared buffer, a counter) keeps the default.
  virtual bool concurrentReads() const { return false; }
};

/// Over a caller-owned array of samples of any SampleType (x fastest, in this host's byte order),
/// converted to float (samplesToFloat) only where the encoder reads: the planes of readSlab, the
/// rows of readRows. The array must outlive the source.
class ArraySource : public VolumeSource {
 public:
  ArraySource(const void* data, SampleType type, Index3 dims, std::string name = "scalars",
              std::array<double, 3> origin = {0, 0, 0}, std::array<double, 3> spacing = {1, 1, 1});
  /// The float32 case.
  ArraySource(const float* data, Index3 dims, std::string name = "scalars",
              std::array<double, 3> origin = {0, 0, 0}, std::array<double, 3> spacing = {1, 1, 1})
      : ArraySource(data, SampleType::Float32, dims, std::move(name), origin, spacing) {}
  Index3 dims() const override { return dims_; }
  std::array<double, 3> origin() const override { return origin_; }
  std::array<double, 3> spacing() const override { return spacing_; }
  std::string name() const override { return name_; }
  void readSlab(int64_t z0, int64_t zCount, float* out) override;
  /// Converts only the rows asked for.
  void readRows(int64_t z0, int64_t zCount, int64_t y0, int64_t yCount, float* out) override;
  int bytesPerVoxel() const override { return sampleTypeSize(type_); }
  /// The array is only read: yes (a subclass that keeps state of its own says no).
  bool concurrentReads() const override { return true; }
  /// Its samples as stored where they are integers of 1 or 2 bytes (a subclass whose readRows
  /// changes samples says none).
  std::optional<SampleType> storedType() const override;
  void readStoredRows(int64_t z0, int64_t zCount, int64_t y0, int64_t yCount, void* out) override;
  SampleType type() const { return type_; }

 private:
  const unsigned char* data_;
  SampleType type_;
  Index3 dims_;
  std::string name_;
  std::array<double, 3> origin_, spacing_;
};

/// A source that reads another and changes some of its samples (marks missing ones: a fill value,
/// a mask): grid, name and sample size are the inner source's, which must outlive it.
class WrappingSource : public VolumeSource {
 public:
  explicit WrappingSource(VolumeSource& inner) : inner_(inner) {}
  Index3 dims() const override { return inner_.dims(); }
  std::array<double, 3> origin() const override { return inner_.origin(); }
  std::array<double, 3> spacing() const override { return inner_.spacing(); }
  std::string name() const override { return inner_.name(); }
  int bytesPerVoxel() const override { return inner_.bytesPerVoxel(); }
  bool readsOnCallingThread() const override { return inner_.readsOnCallingThread(); }
  /// The inner source's: a wrapper's own work on the samples it reads must be thread-safe.
  bool concurrentReads() const override { return inner_.concurrentReads(); }

 protected:
  VolumeSource& inner_;
};

/// Parses name_XxYxZ_type.raw (the convention of shared/data/volumes; type a sampleTypeName, or
/// float or double); false if it does not match.
bool parseRawName(const std::string& path, Index3& dims, SampleType& type);

/// Over a raw little-endian file, converted to float32; reads only the planes asked for, a few
/// megabytes of bytes at a time (each converted while it is in cache), on any number of threads
/// at once (pread and a buffer of the thread's).
class RawFileSource : public VolumeSource {
 public:
  /// Throws IoError if the file cannot be opened, InvalidArgument if its size is not dims * type.
  RawFileSource(const std::string& path, Index3 dims, SampleType type,
                std::array<double, 3> origin = {0, 0, 0},
                std::array<double, 3> spacing = {1, 1, 1});
  ~RawFileSource() override;
  Index3 dims() const override { return dims_; }
  std::array<double, 3> origin() const override { return origin_; }
  std::array<double, 3> spacing() const override { return spacing_; }
  std::string name() const override;
  void readSlab(int64_t z0, int64_t zCount, float* out) override;
  int bytesPerVoxel() const override { return sampleTypeSize(type_); }
  bool concurrentReads() const override { return true; }
  /// Its samples as stored where they are integers of 1 or 2 bytes.
  std::optional<SampleType> storedType() const override;
  void readStoredRows(int64_t z0, int64_t zCount, int64_t y0, int64_t yCount, void* out) override;
  SampleType type() const { return type_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int fd_ = -1;
  Index3 dims_;
  SampleType type_;
  std::array<double, 3> origin_, spacing_;
};

/// The Marschner-Lobb function sampled on dims over [-1, 1]^3, generated plane by plane.
class MarschnerLobbSource : public VolumeSource {
 public:
  explicit MarschnerLobbSource(Index3 dims) : dims_(dims) {}
  Index3 dims() const override { return dims_; }
  std::string name() const override { return "marschner_lobb"; }
  void readSlab(int64_t z0, int64_t zCount, float* out) override;
  bool concurrentReads() const override { return true; }

 private:
  Index3 dims_;
};

}  // namespace afam
