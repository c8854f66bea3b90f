// SPDX-License-Identifier: BSD-3-Clause
// LRU cache of micro-model payloads in RAM, filled by positioned reads from an .afam file.
//
// Budgets: a byte budget and a block-count budget (the paper keeps 200 micro-models); 0 means
// unlimited. Neither is ever exceeded: before a payload is inserted, least-recently-used blocks are
// evicted until it fits. A payload larger than the byte budget on its own is returned to the
// caller without being cached (counted as a miss and a bypass). The byte budget is the memory
// decoded models take, not only the resident ones: a load makes room for its model before it
// reads (the model exists while it is decoded), and the decoding scratch threads hold
// (threadScratchBytes) counts too, so that resident memory follows the budget.
//
// Pinning: the renderer pins the blocks of the frame being rendered (setPinned). Prefetch loads
// (Purpose::Prefetch) never evict a pinned block: when only pinned blocks are left to evict, the
// prefetch load is dropped. Loads of the current frame (Purpose::Frame) may evict pinned blocks
// as a last resort (the frame's earlier blocks are already copied out), so a frame needing more
// than the budget still renders and the budget still holds.
//
// Kept blocks: the resident levels of a frame under a budget (frame_budget.hpp; setKept) are
// never evicted, by frames or prefetching; they count against the budgets like any other block.
// With setFrameEvictsPinned(false) (a frame under a miss budget), frame loads do not evict pinned
// blocks either: a load that finds no room is not read (FrameStats shows the block drawn from a
// coarser level), and the cache does not thrash: it never evicts what the frame draws. A prefetch
// load that finds no room is not read either.
//
// Cold storage (benchmarks): dropOsCache() calls posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED) so
// the next reads come from the device, not the OS page cache; no root needed. The paper disables
// the OS cache; this is the per-point-of-view equivalent.
//
// Storage bandwidth cap (benchmarks): an EMULATION of a slower tier. The cache keeps one virtual
// device clock shared by all threads: a read of B bytes occupies the device for B / cap seconds
// starting when the previous read finished (or now), and the caller sleeps until then, so bytes
// per wall-clock second never exceed the cap. Real read time is included (the sleep only tops it
// up). It models throughput, not seek latency.
//
// Damage: a load whose payload fails its checksum (FormatError) records the entry in the cache's
// DamageLog; getIntact() and prefetch() never read a recorded entry again (damage.hpp).
//
// Time steps: models are kept by their modelKey, which steps of a run share where a block did
// not change (a reference). setFile() moves the cache to another step of the same run: what the
// new step shares with what is resident stays resident and hits, nothing is dropped, and the
// budgets hold across the run. The entries of the API are those of the current step's file;
// prefetch(step, entry) loads from another step (the next one, while this one is shown). A
// residual whose model at the step before is resident is decoded from it: one payload, not the
// chain back to its key step (AfamFile::readPayloadOnto; the same floats).
//
// Stored form: for a caster that decodes payloads itself (a GPU's; setStoredForm), the models it
// decodes are kept as their payloads as stored (CRC-checked, not decoded: a compressed payload
// is 14-55 times smaller than its floats), and the budget counts those bytes. Such a model has no
// floats (CachedModel::stored holds it); PreparedFrame::hostPool decodes it when a frame is cast
// on the CPU after all.
//
// Compact form: a decoded model whose values are integers times a step (an integer-coded
// payload) is kept as a table of its distinct values and a 1- or 2-byte code a control point where
// that is at most three quarters of its floats (CachedModel::compact, block_codec.hpp's
// CompactForm): an 8- or 16-bit scan's samples in 8 or 16 bits, and the budget counts those bytes.
// The casters read the codes through the table (FrameSlot::codeWidth): the same floats.
//
// Thread-safe: the frame thread and one prefetch thread use it concurrently; reads happen outside
// the lock, and a block being loaded by one thread is waited for, not read twice.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "afam/format/afam_file.hpp"
#include "afam/render/cached_model.hpp"
#include "afam/render/damage.hpp"

namespace afam {

struct CacheBudget {
  uint64_t bytes = 0;   ///< 0 = unlimited
  uint64_t blocks = 0;  ///< 0 = unlimited (paper: 200)
};

struct CacheStats {
  uint64_t hits = 0, misses = 0;           ///< frame lookups (get with Purpose::Frame)
  uint64_t bytesRead = 0, blocksRead = 0;  ///< all reads, frame and prefetch
  uint64_t prefetchLoads = 0, prefetchBytes = 0, prefetchDropped = 0;
  uint64_t evictions = 0, bypasses = 0;
  /// Frame loads not read: no room without evicting a pinned or kept block (a frame under a
  /// miss budget, setFrameEvictsPinned(false)).
  uint64_t frameDropped = 0;
  /// Residual models decoded from the resident model of the step before (one payload read and
  /// decoded instead of the chain back to the independent payload).
  uint64_t residualsOnResident = 0;
  double readSeconds = 0;      ///< wall time inside reads, including the bandwidth sleep
  double throttleSeconds = 0;  ///< of which sleeping for the bandwidth cap
};

class LruCache {
 public:
  enum class Purpose { Frame, Prefetch };

  /// damage: the file's damage log, shared with earlier caches of the same file so that a block
  /// is reported and read once per file (null: a new one).
  LruCache(std::shared_ptr<const AfamFile> file, CacheBudget budget,
           std::shared_ptr<DamageLog> damage = nullptr);

  /// Returns the payload of an entry, loading it on a miss. Frame lookups count hits and misses
  /// and mark the block most recently used. Throws what AfamFile::readPayload throws. Null for a
  /// load that finds no room and may not evict (setFrameEvictsPinned(false); prefetching).
  Payload get(int64_t entry, Purpose purpose = Purpose::Frame, bool* wasHit = nullptr);
  /// Like get(), but null for a damaged entry: one found damaged now (recorded in damage()) or
  /// before (not read again). Other errors (I/O) are thrown.
  Payload getIntact(int64_t entry, Purpose purpose = Purpose::Frame);
  /// Prefetch: loads the entry if absent (never evicting pinned blocks) and not known damaged.
  /// Returns true if a read happened; a damaged payload is recorded, not thrown.
  bool prefetch(int64_t entry);
  /// Prefetch from another step of the run (a file setFile() would take).
  bool prefetch(const std::shared_ptr<const AfamFile>& step, int64_t entry);
  bool contains(int64_t entry) const;
  /// Whether the entry's model is known to be damaged (DamageLog).
  bool isDamaged(int64_t entry) const;
  /// Moves to another step of the same run (the same path and partition; InvalidArgument
  /// otherwise), keeping every resident model. Not while a frame is prepared.
  void setFile(std::shared_ptr<const AfamFile> step);
  /// A resident entry's payload, marked most recently used, without counting a lookup (the frame
  /// takes a miss it had loaded for it, which the load counted); null when it is not resident.
  Payload takeLoaded(int64_t entry);
  /// A resident entry's payload, counted as a frame hit and marked most recently used; null
  /// (nothing counted, nothing read) when it is not resident.
  Payload residentHit(int64_t entry);

  /// Entries `form` accepts are loaded in the stored form from now on (null: every load decodes).
  /// Resident models keep the form they were loaded in.
  void setStoredForm(StoredForm form);
  /// Whether decoded models are kept in their compact form where it takes at most kCompactShare
  /// of their floats' bytes (AfamFile::readCompact; on by default): the same values, in a table
  /// and a 1- or 2-byte code a control point. Resident models keep the form they were loaded in.
  void setCompactForm(bool on);
  static constexpr double kCompactShare = 0.75;

  void setPinned(const std::vector<int64_t>& entries);
  void clearPinned();
  /// Blocks never evicted from now on (replacing an earlier set; the current step's entries).
  void setKept(const std::vector<int64_t>& entries);
  /// Whether frame loads may evict pinned blocks as a last resort (true, the default: the exact
  /// frame); false: such a load is not read and get() returns null.
  void setFrameEvictsPinned(bool on);
  /// Called before every read, outside the lock, with the file and the entry (null: none). For
  /// tests: a slow or blocked storage.
  void setLoadHook(std::function<void(const AfamFile&, int64_t)> hook);

  void dropOsCache() const;                     ///< posix_fadvise DONTNEED on the whole file
  void setBandwidthCap(double bytesPerSecond);  ///< 0 = no cap

  CacheStats stats() const;
  void resetStats();
  uint64_t residentBytes() const;
  /// The most bytes resident at any moment since the previous call (or construction); the count
  /// then restarts from the bytes resident now. Never above the byte budget.
  uint64_t takePeakResidentBytes();
  uint64_t residentBlocks() const;
  /// The entries the resident models were loaded for (of whichever step), from most to least
  /// recently used (tests).
  std::vector<int64_t> lruOrder() const;
  const CacheBudget& budget() const { return budget_; }
  const AfamFile& file() const { return *file_; }
  DamageLog& damage() { return *damage_; }
  const std::shared_ptr<DamageLog>& damageLog() const { return damage_; }

 private:
  struct Node {
    Payload data;
    uint64_t bytes = 0;
    std::list<uint64_t>::iterator pos;
    int64_t entry = 0;  ///< what it was loaded for (lruOrder)
  };
  using FilePtr = std::shared_ptr<const AfamFile>;
  FilePtr current() const;  // the current step's file
  Payload getFrom(const FilePtr& f, int64_t entry, Purpose purpose, bool* wasHit);
  Payload getIntactFrom(const FilePtr& f, int64_t entry, Purpose purpose);
  Payload load(const AfamFile& f, int64_t entry);  // read + throttle, outside the lock
  Payload residentModelBefore(const AfamFile& f, int64_t entry);  // a residual's, if resident
  bool makeRoom(uint64_t bytes, bool mayEvictPinned);             // under the lock
  void throttle(uint64_t bytes, std::chrono::steady_clock::time_point readStart);

  std::shared_ptr<const AfamFile> file_;
  CacheBudget budget_;
  std::shared_ptr<DamageLog> damage_;
  mutable std::mutex mutex_;
  std::condition_variable loaded_;
  std::list<uint64_t> lru_;  // model keys, front = most recent
  std::unordered_map<uint64_t, Node> map_;
  std::unordered_set<uint64_t> loading_, pinned_, kept_;
  bool frameEvictsPinned_ = true;
  std::function<void(const AfamFile&, int64_t)> loadHook_;
  uint64_t resident_ = 0;
  uint64_t reserved_ = 0;      // by loads under way, for the models they decode
  uint64_t peakResident_ = 0;  // for takePeakResidentBytes
  CacheStats stats_;
  double capBytesPerSecond_ = 0;
  std::mutex deviceMutex_;
  std::chrono::steady_clock::time_point deviceFree_{};
  StoredForm storedForm_ = nullptr;
  bool compactForm_ = true;
};

}  // namespace afam
