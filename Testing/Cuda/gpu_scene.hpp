// SPDX-License-Identifier: BSD-3-Clause
// Test and benchmark scenes for the GPU ray caster: a volume fitted block by block at every level
// (BlockFitter, fixed NCP fraction), and FrameViews built from any set of blocks, with the host
// arrays they point into. The CPU ray caster and the GPU one render the very same FrameView.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "afam/format/partition.hpp"
#include "afam/render/raycast.hpp"
#include "afam/scene/camera.hpp"
#include "afam/spline/fit.hpp"

namespace afam::gputest {

struct Volume {
  Index3 dims{1, 1, 1};
  std::vector<float> data;  ///< x fastest
  float minValue = 0, maxValue = 0;
};

/// Marschner-Lobb sampled on n^3 points over its domain.
Volume marschnerLobbVolume(int n);
/// A raw file of the shared corpus; type is "uint8", "int16" or "float32". Throws IoError.
Volume loadRawVolume(const std::string& path, Index3 dims, const std::string& type);

/// Every block of every level fitted with degree p and NCP = max(p+1, ceil(ncpFraction * n)).
struct EncodedVolume {
  Partition partition;
  int degree = 2;
  Index3 dims{};
  float minValue = 0, maxValue = 0;
  std::vector<std::vector<FitResult>> models;  ///< [level][linear block index]
  bool raw = false;  ///< DS: models hold padded raw samples (ncp = samples + 2), kSlotRaw
};
EncodedVolume encodeVolume(const Volume& v, int levels, int finestBlocks, int degree,
                           double ncpFraction, int threads = 0);

/// DS: every block of every level as raw samples with one ghost sample per side (clamped at the
/// volume edge), the layout of raycast.hpp's kSlotRaw.
EncodedVolume rawBlocks(const Volume& v, int levels, int finestBlocks);

struct BlockId {
  int level = 0;
  Int3 ijk{};
};

/// Every block of one level.
std::vector<BlockId> wholeLevel(const Partition& p, int level);
/// The paper's distance bands (Core's LodSelector, no culling) for a camera.
std::vector<BlockId> distanceBands(const Partition& p, const Camera& camera);

/// A FrameView and the host arrays it points into. Not copyable (the view points into itself).
struct Frame {
  std::array<std::vector<float>, 3> bounds;
  std::vector<int32_t> cellSlot;
  std::vector<FrameSlot> slots;
  std::vector<uint64_t> keys;  ///< level << 40 | linear index
  std::vector<float> pool;
  std::vector<float> tf;
  FrameView view;
  Frame() = default;
  Frame(const Frame&) = delete;
  Frame& operator=(const Frame&) = delete;
};

struct FrameOptions {
  float sampleDistance = 0.005f;
  bool shaded = true;
  int tfSize = 256;
};

/// Builds the frame for `blocks` (must cover every finest cell at most once) seen by `camera`,
/// with TransferFunction::preset over the volume's value range.
void buildFrame(const EncodedVolume& e, const std::vector<BlockId>& blocks, const Camera& camera,
                const FrameOptions& options, Frame& out);

/// Images: premultiplied float RGBA -> 8-bit over black, and their comparison.
struct ImageDiff {
  int maxAbs8 = 0;         ///< max abs difference per channel, in 1/255 units
  int64_t differing = 0;   ///< pixels whose 8-bit RGB differ at all
  int64_t nonFinite = 0;   ///< GPU pixels that are NaN/Inf (unwritten under poisoning)
  double maxAbsFloat = 0;  ///< on the premultiplied floats
  int64_t pixels = 0;
};
ImageDiff compareImages(const std::vector<float>& cpu, const std::vector<float>& gpu);

/// Where the corpus volumes are: $AFAM_GPU_DATA when it has volumes/, else the repository's
/// Testing/Data (which always has them).
std::string dataDirectory();
/// The points of view of a human exploration: the recorded `name` (user_1.dat, user_2.dat) from
/// $AFAM_TRAJECTORIES or $AFAM_GPU_DATA/trajectories when there, else a generated exploration
/// walk of 400 views (seed 1 for user_1, 2 for user_2). `source` (optional) says which.
std::vector<Pose> explorationPoses(const std::string& name, std::string* source = nullptr);

}  // namespace afam::gputest
