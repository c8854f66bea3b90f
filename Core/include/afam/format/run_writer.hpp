// SPDX-License-Identifier: BSD-3-Clause
// Writes a run of time steps of one grid as one version-3 .afam file (docs/FORMAT.md, "Version
// 3"), atomically: everything goes to PATH.tmp-XXXXXX, which commit() fsyncs and renames onto
// PATH; a writer destroyed or killed before that leaves PATH as it was (temporary_file.hpp).
// Steps come one after another: beginStep(time), every block of every level once (its payload, a
// reference to the same block's model of the step before, unchanged, or a coded residual on that
// model), endStep(). The encoder codes a block against previousModel(), the step before's model
// as a reader decodes it.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "afam/base/slot_cache.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/format/run_layout.hpp"

namespace afam {

class RunWriter {
 public:
  /// `header` describes the grid and the coding (its range is the run's, as docs/FORMAT.md says);
  /// keyInterval K >= 1: a block refers to earlier steps through at most K - 1 references
  /// (canReference() says when one more is allowed); absoluteBound: the bound in data units.
  RunWriter(const std::string& path, const VolumeHeader& header, int keyInterval,
            double absoluteBound);
  /// Opens an existing run to append steps to it in place (docs/FORMAT.md, "Commit slots"): the
  /// bytes of an earlier append that did not commit are cut off first, new payloads, indexes and
  /// the step table go after the committed bytes, and commit() makes them count by writing the
  /// older commit slot last, so that a writer killed at any moment leaves the file with its old or
  /// its new steps. One appender at a time (an exclusive lock; IoError when held). InvalidArgument
  /// for a file of version 1 or 2 (one step: encode the steps as a run), FormatError when damaged.
  static std::unique_ptr<RunWriter> append(const std::string& path);
  ~RunWriter();
  RunWriter(const RunWriter&) = delete;
  RunWriter& operator=(const RunWriter&) = delete;

  /// Starts the next step at `time` (greater than the step before's). InvalidArgument otherwise.
  void beginStep(double time);
  /// A model in its stored form (entry.storedSize bytes), as AfamWriter::addStored. Thread-safe.
  void addStored(const ModelEntry& entryWithoutOffsets, const void* stored);
  /// The block's model of the step before, unchanged; `entry` gives level, block and the error
  /// and range measured on this step's samples. InvalidArgument at step 0, or when
  /// canReference() is false for the block. Thread-safe.
  void addReference(const ModelEntry& entry);
  /// A coded residual on the step before's model of the block (docs/FORMAT.md, in-time coding 2):
  /// the block's model at this step is that model, decoded, plus this payload decoded; `entry`
  /// has the step before's kind and NCP. InvalidArgument when canReference() is false, the kind
  /// or NCP differ, the model before is a constant or the payload is not coded. Thread-safe.
  void addResidual(const ModelEntry& entry, const void* stored);
  /// Ends the step: every block must have been added. valueMin/valueMax: the step's samples.
  void endStep(float valueMin, float valueMax);
  /// Writes the step table and the commit slot, fsyncs and renames onto the path; returns the
  /// file's size in bytes.
  uint64_t commit();

  /// Steps ended so far.
  int64_t stepsDone() const { return static_cast<int64_t>(rows_.size()) - (inStep_ ? 1 : 0); }
  const VolumeHeader& header() const { return header_; }
  double absoluteBound() const { return absoluteBound_; }
  int keyInterval() const { return keyInterval_; }
  /// The time of the last step begun (NaN before the first).
  double lastTime() const;
  const Partition& partition() const { return partition_; }
  /// Whether the current step may refer to the step before for this block (not the first step,
  /// and the block's chain of references stays shorter than the key interval).
  bool canReference(int level, Int3 block) const;
  /// The step before's model of a block: its entry (the owner's payload fields) and decoded
  /// control points. Thread-safe; false at the first step. Each model decoded is kept (up to
  /// kDecodedModelBytes in all) while the block's payload stays the same, so a block that refers
  /// to the step before for many steps is decoded once.
  bool previousModel(int level, Int3 block, ModelEntry& entry, std::vector<float>& control) const;
  /// previousModel's entry alone (nothing decoded); false at the first step.
  bool previousEntry(int level, Int3 block, ModelEntry& entry) const;
  /// The block's slot, in [0, partition().totalBlockCount()): levels coarse to fine, blocks in
  /// the level's linear order. Throws InvalidArgument for a block outside the partition.
  size_t modelSlot(int level, Int3 block) const;
  /// At most this many bytes of decoded models are kept between steps (a 512^3 float32 run's
  /// models take up to about 550 MB).
  static constexpr size_t kDecodedModelBytes = size_t(2) << 30;

 private:
  RunWriter() = default;
  size_t slotOf(const ModelEntry& in) const;
  /// Writes a model's payload after the step's others and fills its entry (under the lock).
  ModelEntry& writePayload(size_t slot, const ModelEntry& in, const void* stored, const char* what);
  uint64_t commitAppend();
  std::string path_, tmpPath_;
  int fd_ = -1;
  bool committed_ = false, inStep_ = false;
  VolumeHeader header_;
  Partition partition_;
  std::vector<int64_t> levelStart_;
  int keyInterval_ = 1;
  double absoluteBound_ = 0;
  bool appending_ = false;   ///< writes go to the file itself (append) rather than a temporary one
  uint64_t generation_ = 0;  ///< of the commit in force (append)
  int nextSlot_ = 1;         ///< the commit slot an append writes
  std::vector<StepRow> rows_;
  std::vector<ModelEntry> current_, previous_;  ///< this step's and the step before's entries
  std::vector<int> depth_, previousDepth_;      ///< steps back to each block's independent payload
  std::vector<std::vector<PayloadPart>> currentChains_, previousChains_;  ///< of residuals
  std::vector<uint8_t> present_;
  uint64_t end_ = 0, payloadSum_ = 0, committedSize_ = 0;
  mutable SlotCache decoded_;  ///< the step before's models, decoded, by slot (previousModel)
  mutable std::mutex mutex_;
};

}  // namespace afam
