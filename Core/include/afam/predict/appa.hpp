// SPDX-License-Identifier: BSD-3-Clause
// APPA, application-aware prefetching (Hongfeng Yu's group), as the paper's renderer uses it: a
// table from quantised camera poses to the blocks visible from them, ordered by importance; at run
// time the last point of view is quantised (its "parent POV") and the table yields the blocks to
// fetch, with no visibility computation on the frame's critical path.
//
// Quantisation (the authors' settings): distance step 0.1 from dMin (poses nearer than dMin use the
// first cell, farther than dMax the last), theta and phi steps of 6 degrees, by flooring as the
// authors do (with a tolerance of 1e-9 cell: a pose on a boundary keeps its cell after the round
// trip through a camera that the predictor's history makes). The blocks of a cell are those visible
// from the cell's sample pose (its centre by default, which is closer on average to the poses that
// fall in the cell than the authors' lower corner; `Corner` reproduces theirs), ordered nearest
// block centre first.
//
// The table is cached beside the .afam file as FILE.afam.appa (layout below), keyed on the .afam
// file (size, modification time, index checksums) and on a context string (LOD and culling
// settings, transfer function, image size) so that a stale or corrupt table is rebuilt, never used.
//   char[8] "AFAPPA\0\0"; u32 version; u64 key; f64 dMin, dStep, angleStep; u32 sampling;
//   u32 nd, nt, np; u32 offsets[nd*nt*np + 1]; u32 entries[offsets[last]];
//   u32 FNV-1a checksum of every preceding byte.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "afam/base/hash.hpp"
#include "afam/scene/camera.hpp"

namespace afam {

class AfamFile;
class LodSelector;

struct AppaGrid {
  enum class Sample : uint32_t { Centre = 0, Corner = 1 };
  double dMin = 1.0, dMax = 2.0, dStep = 0.1, angleStep = 6.0;
  Sample sample = Sample::Centre;
  int distanceCells() const;
  int thetaCells() const;
  int phiCells() const;
  int cellCount() const { return distanceCells() * thetaCells() * phiCells(); }
  /// The cell a pose falls in (floor quantisation, clamped; phi wraps).
  int cellOf(const Pose& pose) const;
  /// The pose whose visible blocks the cell stores.
  Pose samplePose(int cell) const;
};

struct AppaBuildReport {
  bool loadedFromCache = false;
  double seconds = 0;  ///< build (or load) time
  uint64_t bytes = 0;  ///< size of the table file
  int cells = 0;
  uint64_t entries = 0;  ///< block references over all cells
  std::string path;
  std::string rebuiltBecause;  ///< empty when loaded; else why the cached table was not used
};

class AppaTable {
 public:
  static constexpr uint32_t kVersion = 1;
  /// Visible blocks (entry indices) of a pose, most important first.
  using VisibleFn = std::function<std::vector<int64_t>(const Pose&)>;

  AppaTable() = default;
  /// Evaluates `visible` at every cell's sample pose (threads > 1 splits the cells).
  static AppaTable build(const AppaGrid& grid, const VisibleFn& visible, int threads = 1);

  const AppaGrid& grid() const { return grid_; }
  uint64_t key() const { return key_; }
  void setKey(uint64_t key) { key_ = key; }
  /// The blocks stored for the cell of `pose` (pointer range into the table).
  std::pair<const uint32_t*, const uint32_t*> lookup(const Pose& pose) const;
  std::vector<int64_t> blocks(const Pose& pose) const;
  uint64_t entryCount() const { return entries_.size(); }

  /// Writes atomically (temporary file + rename). Throws IoError.
  void save(const std::string& path) const;
  /// Reads and validates. Throws IoError (cannot open) or FormatError (magic, version, truncated,
  /// offsets, checksum) naming the file. Does not check the key: compare key() yourself.
  static AppaTable load(const std::string& path);

  /// The table for a file: loads PATH.appa when its key matches `key` and its grid `grid`, else
  /// builds it (reporting why) and tries to write it back (a read-only directory only loses the
  /// cache, not the table).
  static AppaTable loadOrBuild(const std::string& tablePath, uint64_t key, const AppaGrid& grid,
                               const VisibleFn& visible, AppaBuildReport* report = nullptr,
                               int threads = 1);

 private:
  AppaGrid grid_;
  uint64_t key_ = 0;
  std::vector<uint32_t> offsets_;
  std::vector<uint32_t> entries_;
};

/// Key of a .afam file for the table cache: size, modification time and the index (offsets, sizes,
/// checksums), combined with `context` (settings that change visibility).
uint64_t appaSourceKey(const AfamFile& file, const std::string& context);

/// The visibility APPA stores, computed as the renderer does: the recorded-trajectory camera of the
/// pose (width x height), LodSelector::select with the transfer function, entries ordered by the
/// distance from the eye to the block centre.
AppaTable::VisibleFn makeLodVisibleFn(std::shared_ptr<const AfamFile> file,
                                      const LodSelector& selector, int width, int height,
                                      std::vector<float> tfTable, double tfLo, double tfHi);

}  // namespace afam
