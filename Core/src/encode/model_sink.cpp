// SPDX-License-Identifier: BSD-3-Clause
#include "afam/encode/model_sink.hpp"

#include "afam/base/errors.hpp"
#include "afam/format/run_writer.hpp"

namespace afam {

void InMemoryModels::begin(const VolumeHeader& h) {
  header = h;
  partition = Partition(h.dims, h.levels, h.blocksPerAxis);
  const int64_t total = partition.totalBlockCount();
  entries.assign(size_t(total), ModelEntry{});
  payloads.assign(size_t(total), {});
  stored.assign(size_t(total), {});
  levelStart.assign(size_t(h.levels) + 1, 0);
  for (int l = 0; l < h.levels; ++l)
    levelStart[size_t(l) + 1] = levelStart[size_t(l)] + partition.blockCount(l);
}

int64_t InMemoryModels::entryIndex(int level, Int3 ijk) const {
  if (level < 0 || level >= header.levels) return -1;
  const Int3 b = partition.blocksPerAxis(level);
  for (int a = 0; a < 3; ++a)
    if (ijk[a] < 0 || ijk[a] >= b[a]) return -1;
  return levelStart[size_t(level)] + partition.linearIndex(level, ijk);
}

void InMemoryModels::add(const ModelEntry& entry, const void* bytes) {
  const int64_t i = entryIndex(entry.level, entry.block);
  if (i < 0) throw InvalidArgument("InMemoryModels: block out of range");
  ModelEntry e = entry;
  e.size = decodedBytes(e);
  const auto* b = static_cast<const uint8_t*>(bytes);
  stored[size_t(i)].assign(b, b + e.storedSize);
  payloads[size_t(i)].resize(e.size / 4);
  decodeStoredPayload(e, b, payloads[size_t(i)].data(), "in-memory " + std::to_string(i));
  e.checksum = crc32(bytes, e.storedSize);
  entries[size_t(i)] = e;
}

void InMemoryModels::write(const std::string& path) const {
  AfamWriter w(path, header);
  for (size_t i = 0; i < entries.size(); ++i) w.addStored(entries[i], stored[i].data());
  w.commit();
}

FileModelSink::FileModelSink(std::string path) : path_(std::move(path)) {}

FileModelSink::~FileModelSink() = default;

void FileModelSink::begin(const VolumeHeader& h) {
  if (h.boundKind == BoundKind::Rmse && h.missing == MissingKind::None) {
    writer_ = std::make_unique<AfamWriter>(path_, h);
    return;
  }
  run_ = std::make_unique<RunWriter>(path_, h, 1, absoluteBound(h));
  run_->beginStep(0.0);
  stepMin_ = float(h.valueMin);
  stepMax_ = float(h.valueMax);
}

void FileModelSink::add(const ModelEntry& e, const void* stored) {
  if (run_)
    run_->addStored(e, stored);
  else
    writer_->addStored(e, stored);
}

uint64_t FileModelSink::commit() {
  if (run_) {
    run_->endStep(stepMin_, stepMax_);
    return run_->commit();
  }
  const uint64_t size = writer_->bytesWritten();
  writer_->commit();
  return size;
}

}  // namespace afam
