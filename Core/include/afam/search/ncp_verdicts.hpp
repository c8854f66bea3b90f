// SPDX-License-Identifier: BSD-3-Clause
// The NCP searches of a batch of blocks asked ahead, of a batch of least-squares residuals (on the
// GPU, or the CPU reference: least_squares_batch.hpp): the questions the search would ask its fits
// (smallestPassingNcp, then fewerPointsPerAxis where it refines) answered for all the blocks at
// once, in rounds. Each round replays every unfinished block's search on the verdicts it has and
// asks the residual of the first NCP it has none for. A residual too close to the bound to tell (as
// the CPU's float32 control points would) ends its block's rounds: its fit decides. The encoder
// then searches each block with its verdicts (searchNcp, refineNcpPerAxis): one fit where there
// were about ten, and the same NCPs as without them.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "afam/search/least_squares_batch.hpp"
#include "afam/search/ncp_search.hpp"

namespace afam {

/// How the blocks are searched (the encoder's options).
struct SearchSettings {
  int degree = 2;
  double bound = 0;  ///< the RMSE the searched fits must keep
  SearchMethod method = SearchMethod::Fast;
  int window = 2;
  bool perAxis = true;
};

/// One block to ask ahead for: its samples (x fastest, finite) and shape; its verdicts go to `out`.
/// `probe`: an NCP asked first, whose failing fit ends the block's questions (the encoder's
/// noise probe: a block whose spline needs nearly every sample is stored as its samples).
struct AheadBlock {
  const float* samples = nullptr;
  Int3 n{};
  NcpVerdicts* out = nullptr;
  std::optional<Int3> probe;
  std::optional<std::array<double, 3>> rough;  ///< axisRoughness of the samples, when known
  /// Where its samples are a box of the volume askAhead's `copy` holds: the box's first sample.
  std::optional<Index3> origin;
};

/// What asking ahead took.
struct AheadStats {
  int64_t requests = 0, rounds = 0, unsure = 0;
  double uploadSeconds = 0;    ///< handing the batch's samples over (LeastSquaresBatch::setBlocks)
  double residualSeconds = 0;  ///< waiting for the batch's residuals
};

/// The verdict a residual gives at `bound` for a block of `count` samples: Fails when its RMSE is
/// above the bound beyond double rounding (no control points can do better than least squares),
/// Passes when below it with room for the float32 rounding of the points, else Unknown.
Verdict lsqVerdict(const LsqResidual& r, int64_t count, double bound);

/// Fills every block's verdicts at settings.bound (see the file's comment). Where a round asks
/// fewer than `atOnce` residuals (0: batch.requestsAtOnce()), it also asks those the unfinished
/// searches would ask next, after either verdict of the questions before (breadth first, every
/// block one step deeper at a time): fewer rounds for the same verdicts at the NCPs the searches
/// visit (the others are never consulted). `copy`: where every block has an origin, the volume
/// copy it is a box of (LeastSquaresBatch::setBlocksIn).
AheadStats askAhead(LeastSquaresBatch& batch, const std::vector<AheadBlock>& blocks,
                    const SearchSettings& settings, int64_t atOnce = 0,
                    const LevelSampler* copy = nullptr);

}  // namespace afam
