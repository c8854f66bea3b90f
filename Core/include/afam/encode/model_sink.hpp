// SPDX-License-Identifier: BSD-3-Clause
// Where the encoder's micro-models go: an .afam file (written atomically) or memory.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "afam/format/afam_file.hpp"

namespace afam {

/// Receives the header first, then every model (from the calling thread of encodeVolume).
class ModelSink {
 public:
  virtual ~ModelSink() = default;
  virtual void begin(const VolumeHeader& header) = 0;
  /// `stored` holds entry.storedSize bytes: the payload as the file stores it.
  virtual void add(const ModelEntry& entry, const void* stored) = 0;
};

/// Keeps every model in memory (the tests use it to look at what an encode made).
class InMemoryModels : public ModelSink {
 public:
  void begin(const VolumeHeader& h) override;
  void add(const ModelEntry& entry, const void* stored) override;
  VolumeHeader header;
  Partition partition;
  std::vector<ModelEntry> entries;           ///< ordered like the file: level, then linear index
  std::vector<std::vector<float>> payloads;  ///< same order, decoded control points
  std::vector<std::vector<uint8_t>> stored;  ///< same order, as the file stores them
  std::vector<int64_t> levelStart;
  int64_t entryIndex(int level, Int3 ijk) const;
  /// Writes everything to an .afam file (atomic).
  void write(const std::string& path) const;
};

class RunWriter;

/// Writes to an .afam file through AfamWriter (version 2), or, for a header whose bound is
/// pointwise (BoundKind::MaxError, a field of version 3 only), as a run of one step through
/// RunWriter; nothing is left at the path unless commit() ran.
class FileModelSink : public ModelSink {
 public:
  explicit FileModelSink(std::string path);
  ~FileModelSink() override;
  void begin(const VolumeHeader& h) override;
  void add(const ModelEntry& e, const void* stored) override;
  /// Commits the file; returns its size in bytes.
  uint64_t commit();

 private:
  std::string path_;
  std::unique_ptr<AfamWriter> writer_;
  std::unique_ptr<RunWriter> run_;
  float stepMin_ = 0, stepMax_ = 0;
};

}  // namespace afam
