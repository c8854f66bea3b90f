// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <cmath>
#include <numeric>

#include "afam/render/frame_budget.hpp"
#include "afam/scene/transfer_function.hpp"

namespace afam {

double blockImportance(const AfamFile& file, const Camera& camera, const BlockRef& block,
                       int levelsAdded, const std::vector<float>& tf, double tfLo, double tfHi) {
  double lo[3], hi[3];
  blockBox(file.partition(), block.level, block.ijk, lo, hi);
  Vec3 toCentre{};
  double diagonal2 = 0;
  for (int a = 0; a < 3; ++a) {
    toCentre[size_t(a)] = 0.5 * (lo[a] + hi[a]) - camera.eye[size_t(a)];
    diagonal2 += (hi[a] - lo[a]) * (hi[a] - lo[a]);
  }
  const double diagonal = std::sqrt(diagonal2);
  const double distance = std::sqrt(dot(toCentre, toCentre));
  // Angular size, at most that of a block around the eye.
  const double size = diagonal / std::max(distance, 0.5 * diagonal);
  // Nearness to the view's centre: the angle off the view axis in half fields of view.
  const double along = distance > 0 ? dot(toCentre, camera.forward) / distance : 1.0;
  const double offAxis = std::acos(std::clamp(along, -1.0, 1.0));
  const double halfField = std::max(1e-3, std::atan(std::max(camera.tanHalfX, camera.tanHalfY)));
  const double central = 1.0 / (1.0 + (offAxis / halfField) * (offAxis / halfField));
  const ModelEntry& e = file.entries()[size_t(block.entry)];
  const double opacity =
      tf.empty() ? 1.0 : TransferFunction::maxOpacity(tf, tfLo, tfHi, e.minValue, e.maxValue);
  return size * central * opacity * double(std::max(0, levelsAdded));
}

std::vector<int64_t> importanceOrder(const AfamFile& file, const Camera& camera,
                                     const std::vector<BlockRef>& blocks,
                                     const std::function<int(const BlockRef&)>& standInLevel,
                                     const std::vector<float>& tf, double tfLo, double tfHi) {
  std::vector<double> score(blocks.size());
  for (size_t i = 0; i < blocks.size(); ++i)
    score[i] = blockImportance(file, camera, blocks[i], blocks[i].level - standInLevel(blocks[i]),
                               tf, tfLo, tfHi);
  std::vector<size_t> order(blocks.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return score[a] > score[b]; });
  std::vector<int64_t> out;
  out.reserve(order.size());
  for (const size_t i : order) out.push_back(blocks[i].entry);
  return out;
}

}  // namespace afam
