// SPDX-License-Identifier: BSD-3-Clause
// Format version 3, a run of time steps in one file (docs/FORMAT.md): reading one step's models
// (AfamFile::open(path, step) comes here after the header) and RunWriter.
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>

#include "afam/base/errors.hpp"
#include "afam/format/block_codec.hpp"
#include "afam/format/run_layout.hpp"
#include "afam/format/run_writer.hpp"
#include "afam/format/temporary_file.hpp"
#include "file_layout.hpp"

namespace afam {

namespace {

constexpr uint16_t kReferenceFlag = 1u << 10;  // flags bits 10-11: 1 reference
constexpr uint16_t kResidualFlag = 2u << 10;   // 2 residual
constexpr uint16_t kTemporalMask = 3u << 10;
constexpr size_t kEntryBytes = sizeof(layout::IndexEntryV1);

}  // namespace

namespace layout {

namespace {

/// Checks of the header fields version 3 gives a meaning, and the commit record they point to.
CommitRecord readCommit(const AfamFile& f, const FileHeader& h, int fd) {
  const std::string& path = f.path();
  const auto bad = [&](const std::string& what) { return FormatError(path + ": " + what); };
  if (h.entryCount != static_cast<uint64_t>(f.partition().totalBlockCount()))
    throw bad("index count " + std::to_string(h.entryCount) + " does not match the " +
              std::to_string(f.partition().totalBlockCount()) + " blocks of the partition");
  if (h.keyInterval < 1) throw bad("key interval 0");
  if (h.boundKind > static_cast<uint8_t>(BoundKind::MaxError))
    throw bad("bound kind " + std::to_string(h.boundKind) + " is not read by this version");
  if (f.fileSize() < kRunStepsOffset) throw bad("truncated: no commit slots");
  uint8_t slots[2 * kCommitSlotBytes];
  preadAll(fd, slots, sizeof slots, kCommitSlotsOffset, path, "commit slots");
  const CommitRecord r = chooseCommit(slots, slots + kCommitSlotBytes, path).record;
  if (r.committedSize > f.fileSize())
    throw bad("truncated: " + std::to_string(f.fileSize()) + " bytes, the commit says " +
              std::to_string(r.committedSize));
  if (r.stepCount == 0 || r.stepCount > r.committedSize / 32 ||
      r.stepTableOffset < kRunStepsOffset || r.stepTableOffset % 8 != 0 ||
      r.stepTableOffset + stepTableBytes(r.stepCount) != r.committedSize)
    throw bad("commit slot inconsistent (" + std::to_string(r.stepCount) +
              " steps, step table at " + std::to_string(r.stepTableOffset) + ", " +
              std::to_string(r.committedSize) + " bytes committed)");
  return r;
}

/// Step s's index, checked against its CRC.
std::vector<IndexEntryV1> readStepIndex(int fd, const std::string& path, const StepRow& row,
                                        uint64_t entries, int64_t s) {
  std::vector<IndexEntryV1> raw(entries);
  preadAll(fd, raw.data(), entries * kEntryBytes, row.indexOffset, path,
           "index of step " + std::to_string(s));
  if (crc32(raw.data(), entries * kEntryBytes) != row.indexChecksum)
    throw FormatError(path + ": index of step " + std::to_string(s) +
                      " checksum mismatch (index damaged)");
  return raw;
}

/// The payload of one block's entry (independent or a residual) checked against the step that
/// holds it: inside that step's payloads and aligned.
PayloadPart payloadPart(const IndexEntryV1& r, const ModelEntry& parsed, const StepRow& row,
                        int64_t s, uint32_t alignment, const std::string& where) {
  const uint64_t end = row.indexOffset;
  if (r.offset < kRunStepsOffset || r.offset % alignment != 0 || r.offset > end ||
      parsed.storedSize > end - r.offset)
    throw FormatError(where + ": payload [" + std::to_string(r.offset) + ", +" +
                      std::to_string(parsed.storedSize) + ") lies outside step " +
                      std::to_string(s) + "'s payloads or is misaligned");
  PayloadPart p;
  p.offset = r.offset;
  p.storedSize = parsed.storedSize;
  p.checksum = r.checksum;
  p.coded = parsed.coded;
  p.integerCoded = parsed.integerCoded;
  p.lanesCoded = parsed.lanesCoded;
  p.roundedPoints = parsed.roundedPoints;
  p.step = s;
  return p;
}

/// Resolves block i at `step` through time: references skipped (the model is the step before's),
/// residuals collected, down to the independent payload; at most K - 1 steps back. Fills m's
/// kind, NCP, sizes and payload (the last residual's, with the chain) from what it finds.
template <typename IndexOf>
void resolveInTime(IndexOf& index, const std::vector<StepRow>& rows, const FileHeader& h,
                   int64_t step, size_t i, const BlockExtent& extent, const VolumeHeader& vh,
                   const std::string& where, ModelEntry& m, std::vector<PayloadPart>& chain) {
  std::vector<PayloadPart> parts;  // newest first
  ModelEntry parsed;
  bool kindKnown = false;
  int64_t owner = -1;  // the step of the newest payload
  for (int64_t s = step;; --s) {
    const IndexEntryV1& r = index(s)[i];
    const uint16_t inTime = r.flags & kTemporalMask;
    if (inTime == kTemporalMask)
      throw FormatError(where + ": in-time coding 3 at step " + std::to_string(s));
    if (inTime != 0 && (s == 0 || rows[size_t(s)].keyStep))
      throw FormatError(where + ": " + (inTime == kReferenceFlag ? "a reference" : "a residual") +
                        " at step " + std::to_string(s) +
                        (s == 0 ? ", the first" : ", a key step"));
    if (inTime != 0 && step - s + 1 >= static_cast<int64_t>(h.keyInterval))
      throw FormatError(where + ": coding in time runs past the key interval " +
                        std::to_string(h.keyInterval));
    if (inTime != 0 && (r.flags & kMaskedFlag) != 0)
      throw FormatError(where + ": a masked block coded in time at step " + std::to_string(s));
    if (inTime == kReferenceFlag) {
      if (r.offset != 0 || r.storedBytes != 0 || r.checksum != 0)
        throw FormatError(where + ": a reference with a payload");
      continue;
    }
    ModelEntry e;
    parseEntry(r, 3, vh, extent, where, e, kTemporalMask | kMaskedFlag);
    if (s < step && (e.masked || e.kind == BlockKind::Empty))
      throw FormatError(where + ": step " + std::to_string(step) + " is coded in time on step " +
                        std::to_string(s) + "'s " + (e.masked ? "masked" : "empty") + " block");
    if (e.kind == BlockKind::Empty) {  // no payload: the walk ends here
      parsed = e;
      owner = s;
      break;
    }
    if (inTime == kResidualFlag && e.kind == BlockKind::Constant)
      throw FormatError(where + ": a residual on a constant at step " + std::to_string(s));
    if (inTime == kResidualFlag && e.roundedPoints)
      throw FormatError(where + ": a residual with rounded points at step " + std::to_string(s));
    if (kindKnown && (e.kind != parsed.kind || e.ncp != parsed.ncp))
      throw FormatError(where + ": step " + std::to_string(s) + "'s " + blockKindName(e.kind) +
                        " does not match the residual on it");
    if (!kindKnown) owner = s;
    parsed = e;
    kindKnown = true;
    parts.push_back(payloadPart(r, e, rows[size_t(s)], s, h.payloadAlignment, where));
    if (inTime == 0) break;
  }
  m.masked = parsed.masked;
  if (parts.empty()) {  // an empty block: no payload
    const int level = m.level;
    const Int3 block = m.block;
    m = parsed;
    m.level = level;
    m.block = block;
    m.ownerStep = owner;
    chain.clear();
    return;
  }
  const PayloadPart newest = parts.front();
  m.kind = parsed.kind;
  m.ncp = parsed.ncp;
  m.degree = parsed.degree;
  m.samples = parsed.samples;
  m.size = parsed.size;
  m.coded = newest.coded;
  m.integerCoded = newest.integerCoded;
  m.lanesCoded = newest.lanesCoded;
  m.roundedPoints = newest.roundedPoints;
  m.storedSize = newest.storedSize;
  m.offset = newest.offset;
  m.checksum = newest.checksum;
  m.reference = owner != step;
  m.ownerStep = owner;
  m.residual = parts.size() > 1;
  m.chainLength = static_cast<uint32_t>(parts.size());
  chain.assign(parts.rbegin(), parts.rend());
}

}  // namespace

void openRunStep(AfamFile& f, const FileHeader& h, int64_t step) {
  const std::string& path = f.path_;
  const CommitRecord commit = readCommit(f, h, f.fd_);
  std::vector<uint8_t> table(stepTableBytes(commit.stepCount));
  preadAll(f.fd_, table.data(), table.size(), commit.stepTableOffset, path, "step table");
  const uint64_t E = h.entryCount;
  const std::vector<StepRow> rows = decodeStepTable(table.data(), commit.stepCount,
                                                    commit.stepTableOffset, E * kEntryBytes, path);
  if (step < 0 || step >= static_cast<int64_t>(rows.size()))
    throw InvalidArgument(path + ": step " + std::to_string(step) + " of a run of " +
                          std::to_string(rows.size()) + " steps");
  f.stepTimes_.clear();
  for (const StepRow& r : rows) f.stepTimes_.push_back(r.time);
  f.step_ = step;
  f.keyInterval_ = static_cast<int>(std::min<uint32_t>(h.keyInterval, 1u << 30));
  f.payloadOffset_ = kRunStepsOffset;
  std::map<int64_t, std::vector<IndexEntryV1>> indices;  // the steps a reference walks through
  const auto index = [&](int64_t s) -> const std::vector<IndexEntryV1>& {
    auto it = indices.find(s);
    if (it == indices.end())
      it = indices.emplace(s, readStepIndex(f.fd_, path, rows[size_t(s)], E, s)).first;
    return it->second;
  };
  const VolumeHeader& vh = f.header_;
  const Partition& part = f.partition_;
  f.entries_.resize(E);
  f.chains_.clear();
  std::vector<PayloadPart> chain;
  int level = 0;
  for (size_t i = 0; i < E; ++i) {
    while (static_cast<int64_t>(i) >= f.levelStart_[static_cast<size_t>(level) + 1]) ++level;
    const Int3 ijk =
        part.blockFromLinear(level, static_cast<int64_t>(i) - f.levelStart_[size_t(level)]);
    const std::string where = path + ": step " + std::to_string(step) + ", index entry " +
                              std::to_string(i) + " (" + Partition::blockName(level, ijk) + ")";
    const IndexEntryV1& own = index(step)[i];
    ModelEntry& m = f.entries_[i];
    m.level = level;
    m.block = ijk;
    resolveInTime(index, rows, h, step, i, part.extent(level, ijk), vh, where, m, chain);
    if (m.residual) f.chains_[static_cast<int64_t>(i)] = chain;
    m.minValue = own.minValue;
    m.maxValue = own.maxValue;
    m.rmse = own.rmse;
    m.maxError = own.maxError;
  }
}

}  // namespace layout

using namespace layout;

RunWriter::RunWriter(const std::string& path, const VolumeHeader& header, int keyInterval,
                     double absoluteBound)
    : path_(path), header_(header), keyInterval_(keyInterval), absoluteBound_(absoluteBound) {
  if (keyInterval < 1)
    throw InvalidArgument("run writer: key interval " + std::to_string(keyInterval) + " < 1");
  if (header.degree < 1 || header.degree > 5)
    throw InvalidArgument("run writer: degree " + std::to_string(header.degree) +
                          " outside [1, 5]");
  if (header.levels < 1 || header.levels > kMaxLevels)
    throw InvalidArgument("run writer: levels outside [1, 16]");
  partition_ = Partition(header.dims, header.levels, header.blocksPerAxis);
  if (partition_.totalBlockCount() > (int64_t(1) << 31))
    throw InvalidArgument("run writer: more than 2^31 micro-blocks");
  levelStart_ = levelStarts(partition_, header.levels);
  end_ = kRunStepsOffset;
  removeStaleTemporaries(path);
  fd_ = createLockedTemporary(path, tmpPath_);
}

RunWriter::~RunWriter() {
  if (appending_) {  // the file keeps its committed steps; what this writer added is cut off
    // Only a writer that holds the lock and knows the committed size cuts anything.
    if (fd_ >= 0 && !committed_ && committedSize_ > 0)
      if (::ftruncate(fd_, static_cast<off_t>(committedSize_)) != 0) {
        // Nothing to report from a destructor: the lock goes with the descriptor below.
      }
    if (fd_ >= 0) ::close(fd_);
    return;
  }
  if (fd_ >= 0) ::close(fd_);
  if (!committed_ && !tmpPath_.empty()) ::unlink(tmpPath_.c_str());
}

double RunWriter::lastTime() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return rows_.empty() ? std::numeric_limits<double>::quiet_NaN() : rows_.back().time;
}

std::unique_ptr<RunWriter> RunWriter::append(const std::string& path) {
  const int64_t steps = AfamFile::open(path)->stepCount();
  const auto last = AfamFile::open(path, steps - 1);
  if (last->version() != kRunVersion)
    throw InvalidArgument(path + ": format version " + std::to_string(last->version()) +
                          " holds one step; appending needs a run (encode its steps as one)");
  std::unique_ptr<RunWriter> w(new RunWriter());
  w->path_ = w->tmpPath_ = path;  // writes and their messages go to the file itself
  w->header_ = last->header();
  w->partition_ = last->partition();
  w->levelStart_ = levelStarts(w->partition_, w->header_.levels);
  w->keyInterval_ = last->keyInterval();
  w->appending_ = true;
  w->fd_ = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
  if (w->fd_ < 0) throw IoError(path + ": cannot open to append: " + sysError());
  if (::flock(w->fd_, LOCK_EX | LOCK_NB) != 0)
    throw IoError(path + ": another writer is appending to it");
  FileHeader h{};
  preadAll(w->fd_, &h, sizeof h, 0, path, "header");
  w->absoluteBound_ = h.absoluteBound;
  uint8_t slots[2 * kCommitSlotBytes];
  preadAll(w->fd_, slots, sizeof slots, kCommitSlotsOffset, path, "commit slots");
  const CommitChoice choice = chooseCommit(slots, slots + kCommitSlotBytes, path);
  const CommitRecord& r = choice.record;
  std::vector<uint8_t> table(stepTableBytes(r.stepCount));
  preadAll(w->fd_, table.data(), table.size(), r.stepTableOffset, path, "step table");
  w->rows_ = decodeStepTable(table.data(), r.stepCount, r.stepTableOffset,
                             h.entryCount * kEntryBytes, path);
  // What an append that did not commit left after the committed bytes goes.
  if (::ftruncate(w->fd_, static_cast<off_t>(r.committedSize)) != 0)
    throw IoError(path + ": cannot cut off an unfinished append: " + sysError());
  w->committedSize_ = r.committedSize;
  w->end_ = r.committedSize;
  w->payloadSum_ = r.totalPayloadBytes;
  w->generation_ = r.generation;
  w->nextSlot_ = choice.nextSlot;
  w->previous_ = last->entries();
  const size_t E = w->previous_.size();
  w->previousChains_.resize(E);
  w->previousDepth_.resize(E);
  for (size_t i = 0; i < E; ++i) {  // depth: steps back to the independent payload
    w->previousChains_[i] = last->chain(static_cast<int64_t>(i));
    const ModelEntry& m = w->previous_[i];
    const int64_t base = m.residual ? w->previousChains_[i].front().step : m.ownerStep;
    w->previousDepth_[i] = static_cast<int>(steps - 1 - base);
  }
  return w;
}

size_t RunWriter::slotOf(const ModelEntry& in) const {
  if (in.level < 0 || in.level >= header_.levels)
    throw InvalidArgument(path_ + ": level " + std::to_string(in.level) + " out of range");
  const Int3 b = partition_.blocksPerAxis(in.level);
  for (int a = 0; a < 3; ++a)
    if (in.block[a] < 0 || in.block[a] >= b[a])
      throw InvalidArgument(path_ + ": " + Partition::blockName(in.level, in.block) +
                            " out of range");
  return static_cast<size_t>(levelStart_[size_t(in.level)] +
                             partition_.linearIndex(in.level, in.block));
}

void RunWriter::beginStep(double time) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (committed_ || inStep_)
    throw InvalidArgument(path_ + ": beginStep inside a step or after commit");
  if (!std::isfinite(time) || (!rows_.empty() && !(time > rows_.back().time)))
    throw InvalidArgument(
        path_ + ": step time " + std::to_string(time) + " does not follow " +
        (rows_.empty() ? std::string("(none)") : std::to_string(rows_.back().time)));
  const size_t E = static_cast<size_t>(partition_.totalBlockCount());
  if (decoded_.slots() != E) decoded_.reset(E, kDecodedModelBytes);
  current_.assign(E, ModelEntry{});
  currentChains_.assign(E, {});
  depth_.assign(E, 0);
  present_.assign(E, 0);
  StepRow row;
  row.time = time;
  rows_.push_back(row);  // completed by endStep
  inStep_ = true;
}

ModelEntry& RunWriter::writePayload(size_t slot, const ModelEntry& in, const void* stored,
                                    const char* what) {
  const uint64_t bytes = in.storedSize;
  const uint32_t crc = crc32(stored, bytes);
  if (!inStep_) throw InvalidArgument(path_ + ": " + what + " outside a step");
  if (present_[slot])
    throw InvalidArgument(path_ + ": " + Partition::blockName(in.level, in.block) + " added twice");
  const uint64_t offset = end_;
  pwriteAll(fd_, stored, bytes, offset, tmpPath_);
  end_ = alignUp(offset + bytes, kPayloadAlign);
  payloadSum_ += bytes;
  ModelEntry& m = current_[slot];
  m = in;
  m.integerCoded = storedIsIntegerCoded(in, stored);
  m.lanesCoded = storedIsLanesCoded(in, stored);
  m.offset = offset;
  m.size = decodedBytes(in);
  m.checksum = crc;
  m.reference = false;
  m.residual = false;
  m.chainLength = 1;
  m.ownerStep = static_cast<int64_t>(rows_.size()) - 1;
  present_[slot] = 1;
  return m;
}

void RunWriter::addStored(const ModelEntry& in, const void* stored) {
  const size_t slot = checkModelToWrite(path_, header_, partition_, levelStart_, in);
  std::lock_guard<std::mutex> lock(mutex_);
  writePayload(slot, in, stored, "addStored");
  depth_[slot] = 0;
}

bool RunWriter::canReference(int level, Int3 block) const {
  const size_t slot = modelSlot(level, block);
  return !previous_.empty() && previousDepth_[slot] + 1 < keyInterval_ && !previous_[slot].masked &&
         previous_[slot].kind != BlockKind::Empty;
}

void RunWriter::addReference(const ModelEntry& in) {
  const size_t slot = slotOf(in);
  std::lock_guard<std::mutex> lock(mutex_);
  if (!inStep_) throw InvalidArgument(path_ + ": addReference outside a step");
  const std::string name = Partition::blockName(in.level, in.block);
  if (present_[slot]) throw InvalidArgument(path_ + ": " + name + " added twice");
  if (previous_.empty() || previousDepth_[slot] + 1 >= keyInterval_ || previous_[slot].masked ||
      previous_[slot].kind == BlockKind::Empty)
    throw InvalidArgument(path_ + ": " + name + " cannot refer to the step before (" +
                          (previous_.empty() ? std::string("first step")
                           : previousDepth_[slot] + 1 >= keyInterval_
                               ? "key interval " + std::to_string(keyInterval_)
                               : "a masked or empty block") +
                          ")");
  ModelEntry& m = current_[slot];
  m = previous_[slot];  // the owner's payload, kind and NCP
  currentChains_[slot] = previousChains_[slot];
  m.minValue = in.minValue;
  m.maxValue = in.maxValue;
  m.rmse = in.rmse;
  m.maxError = in.maxError;
  m.reference = true;
  depth_[slot] = previousDepth_[slot] + 1;
  present_[slot] = 1;
}

void RunWriter::addResidual(const ModelEntry& in, const void* stored) {
  const size_t slot = checkModelToWrite(path_, header_, partition_, levelStart_, in);
  const std::string name = Partition::blockName(in.level, in.block);
  if (!in.coded) throw InvalidArgument(path_ + ": " + name + ": a residual must be coded");
  if (in.roundedPoints)
    throw InvalidArgument(path_ + ": " + name + ": a residual cannot have rounded points");
  std::lock_guard<std::mutex> lock(mutex_);
  if (inStep_ && (previous_.empty() || previousDepth_[slot] + 1 >= keyInterval_))
    throw InvalidArgument(path_ + ": " + name + " cannot be coded on the step before");
  const ModelEntry& before = inStep_ ? previous_[slot] : in;
  if (in.masked || before.masked || before.kind == BlockKind::Empty)
    throw InvalidArgument(path_ + ": " + name + ": masked and empty blocks are not coded in time");
  if (before.kind == BlockKind::Constant || before.kind != in.kind || before.ncp != in.ncp)
    throw InvalidArgument(path_ + ": " + name + ": a residual's kind and NCP must be the step " +
                          "before's (" + blockKindName(before.kind) + ")");
  ModelEntry& m = writePayload(slot, in, stored, "addResidual");
  m.residual = true;
  std::vector<PayloadPart>& chain = currentChains_[slot];
  chain = previousChains_[slot];
  if (chain.empty())  // the step before's model is one payload: the chain's first
    chain.push_back(PayloadPart{before.offset, before.storedSize, before.checksum, before.coded,
                                before.integerCoded, before.ownerStep, before.lanesCoded,
                                before.roundedPoints});
  chain.push_back(PayloadPart{m.offset, m.storedSize, m.checksum, true, m.integerCoded, m.ownerStep,
                              m.lanesCoded, false});
  m.chainLength = static_cast<uint32_t>(chain.size());
  depth_[slot] = previousDepth_[slot] + 1;
}

size_t RunWriter::modelSlot(int level, Int3 block) const {
  ModelEntry probe;
  probe.level = level;
  probe.block = block;
  return slotOf(probe);
}

bool RunWriter::previousEntry(int level, Int3 block, ModelEntry& entry) const {
  if (previous_.empty()) return false;
  entry = previous_.at(modelSlot(level, block));
  return true;
}

bool RunWriter::previousModel(int level, Int3 block, ModelEntry& entry,
                              std::vector<float>& control) const {
  if (previous_.empty()) return false;
  const size_t slot = modelSlot(level, block);
  entry = previous_.at(slot);
  // A payload's offset names its model: a reference keeps its owner's, a residual has its own.
  if (decoded_.find(slot, entry.offset, control)) return true;
  control.resize(entry.size / sizeof(float));
  if (entry.residual) {  // from the model before its newest residual where that one is kept
    const std::vector<PayloadPart>& chain = previousChains_.at(slot);
    thread_local std::vector<float> before;
    const bool kept = chain.size() >= 2 &&
                      decoded_.find(slot, chain[chain.size() - 2].offset, before) &&
                      before.size() == control.size();
    decodeChain(fd_, tmpPath_, entry, chain, kept ? before.data() : nullptr, control.data());
  } else {
    std::vector<uint8_t> stored(entry.storedSize);
    preadAll(fd_, stored.data(), stored.size(), entry.offset, tmpPath_, "a previous payload");
    decodeStoredPayload(entry, stored.data(), control.data(),
                        path_ + ": " + Partition::blockName(level, block));
  }
  decoded_.put(slot, entry.offset, control);
  return true;
}

void RunWriter::endStep(float valueMin, float valueMax) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!inStep_) throw InvalidArgument(path_ + ": endStep outside a step");
  std::vector<IndexEntryV1> raw(current_.size());
  bool key = true;
  for (size_t i = 0; i < current_.size(); ++i) {
    if (!present_[i]) {
      int level = 0;
      while (static_cast<int64_t>(i) >= levelStart_[size_t(level) + 1]) ++level;
      throw InvalidArgument(
          path_ + ": step " + std::to_string(rows_.size() - 1) + " without " +
          Partition::blockName(
              level, partition_.blockFromLinear(level, int64_t(i) - levelStart_[size_t(level)])));
    }
    const ModelEntry& m = current_[i];
    raw[i] = rawEntry(m, m.reference ? kReferenceFlag : m.residual ? kResidualFlag : 0);
    if (m.residual) key = false;
    if (m.reference) {
      raw[i].offset = 0;
      raw[i].storedBytes = 0;
      raw[i].checksum = 0;
      key = false;
    }
  }
  StepRow& row = rows_.back();
  row.indexOffset = alignUp(end_, 8);
  row.indexChecksum = crc32(raw.data(), raw.size() * kEntryBytes);
  row.keyStep = key;
  row.valueMin = valueMin;
  row.valueMax = valueMax;
  pwriteAll(fd_, raw.data(), raw.size() * kEntryBytes, row.indexOffset, tmpPath_);
  end_ = row.indexOffset + raw.size() * kEntryBytes;
  previous_.swap(current_);
  previousChains_.swap(currentChains_);
  previousDepth_.swap(depth_);
  inStep_ = false;
}

uint64_t RunWriter::commitAppend() {
  // New step table after everything, on disk before the slot that points to it.
  const std::vector<uint8_t> table = encodeStepTable(rows_);
  CommitRecord r;
  r.generation = generation_ + 1;
  r.stepCount = rows_.size();
  r.stepTableOffset = alignUp(end_, 8);
  r.committedSize = r.stepTableOffset + table.size();
  r.totalPayloadBytes = payloadSum_;
  pwriteAll(fd_, table.data(), table.size(), r.stepTableOffset, path_);
  if (::fsync(fd_) != 0) throw IoError(path_ + ": fsync failed: " + sysError());
  const auto slot = encodeCommitSlot(r);
  pwriteAll(fd_, slot.data(), slot.size(),
            kCommitSlotsOffset + kCommitSlotBytes * uint64_t(nextSlot_), path_);
  committed_ = true;  // from here on nothing is cut off: the slot may already be on disk
  committedSize_ = r.committedSize;
  const bool synced = ::fsync(fd_) == 0;
  ::close(fd_);  // releases the lock
  fd_ = -1;
  if (!synced) throw IoError(path_ + ": fsync of the commit slot failed: " + sysError());
  return committedSize_;
}

uint64_t RunWriter::commit() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (committed_) return committedSize_;
  if (inStep_ || rows_.empty())
    throw InvalidArgument(path_ + ": commit " + (inStep_ ? "inside a step" : "without a step"));
  if (appending_) return commitAppend();
  const std::vector<uint8_t> table = encodeStepTable(rows_);
  CommitRecord r;
  r.generation = 1;
  r.stepCount = rows_.size();
  r.stepTableOffset = alignUp(end_, 8);
  r.committedSize = r.stepTableOffset + table.size();
  r.totalPayloadBytes = payloadSum_;
  FileHeader h = makeFileHeader(header_, partition_, kRunVersion);
  h.entryCount = static_cast<uint64_t>(partition_.totalBlockCount());
  h.keyInterval = static_cast<uint32_t>(keyInterval_);
  h.absoluteBound = absoluteBound_;
  h.headerChecksum = crc32(&h, offsetof(FileHeader, headerChecksum));
  const auto slotA = encodeCommitSlot(r);
  const std::array<uint8_t, kCommitSlotBytes> slotB{};
  commitTemporary(fd_, tmpPath_, path_, r.committedSize, [&] {
    pwriteAll(fd_, table.data(), table.size(), r.stepTableOffset, tmpPath_);
    pwriteAll(fd_, &h, sizeof h, 0, tmpPath_);
    pwriteAll(fd_, slotA.data(), slotA.size(), kCommitSlotsOffset, tmpPath_);
    pwriteAll(fd_, slotB.data(), slotB.size(), kCommitSlotsOffset + kCommitSlotBytes, tmpPath_);
  });
  committed_ = true;
  committedSize_ = r.committedSize;
  return committedSize_;
}

}  // namespace afam
