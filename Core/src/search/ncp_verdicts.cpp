// SPDX-License-Identifier: BSD-3-Clause
#include "afam/search/ncp_verdicts.hpp"

#include <algorithm>
#include <chrono>
#include <optional>

#include "afam/spline/fit.hpp"

namespace afam {

namespace {

/// Verdicts a replay takes as given beside the known ones (a branch of the search asked ahead of
/// the verdicts before it): passes or fails.
using Assumed = std::vector<std::pair<Int3, bool>>;

/// One block's replay: its search on its verdicts alone (and `assumed`). `ask` gets the first NCP
/// without one; `unsure` is set at an NCP whose residual could not tell.
struct Replay {
  const AheadBlock& block;
  const SearchSettings& s;
  std::optional<std::array<double, 3>>& rough;
  const Assumed& assumed;
  std::optional<Int3> ask;
  bool unsure = false;

  bool pass(Int3 ncp) {
    if (ask || unsure) return false;  // the rest of this replay is not asked yet
    for (const auto& [at, v] : block.out->known)
      if (at == ncp) {
        unsure = v == Verdict::Unknown;
        return v == Verdict::Passes;
      }
    for (const auto& [at, passes] : assumed)
      if (at == ncp) return passes;
    ask = ncp;
    return false;
  }

  void run() {
    const Int3 n = block.n;
    Int3 degs{};
    for (int a = 0; a < 3; ++a) degs[a] = effectiveDegree(s.degree, n[a]);
    if (block.probe && !pass(*block.probe)) return;  // noise (or asked, or unsure)
    const int hi = std::max({1, n[0], n[1], n[2]}), lo = std::min(s.degree + 1, hi);
    const int k = smallestPassingNcp(lo, hi, s.method, s.window,
                                     [&](int c) { return pass(clampNcp(c, n, degs)); });
    if (ask || unsure || !s.perAxis || k > hi || k == lo) return;  // refines complex passing fits
    if (!rough) rough = axisRoughness(block.samples, n);
    fewerPointsPerAxis(*rough, clampNcp(k, n, degs), n, s.degree, [&](Int3 c) { return pass(c); });
  }
};

/// A search's question asked ahead: its block, the verdicts assumed on the way to it, its NCP.
struct Branch {
  size_t block;
  Assumed assumed;
  Int3 ncp;
};

/// One round's requests: every unfinished block's next question (`open` cleared for the finished
/// ones), then, while fewer than atOnce, the questions after either verdict of the deepest asked,
/// a level of every block's branches at a time.
std::vector<LsqRequest> roundRequests(const std::vector<AheadBlock>& blocks,
                                      const SearchSettings& settings,
                                      std::vector<std::optional<std::array<double, 3>>>& rough,
                                      std::vector<uint8_t>& open, int64_t atOnce,
                                      AheadStats& stats) {
  std::vector<LsqRequest> requests;
  std::vector<Branch> deepest;
  const Assumed none;
  for (size_t b = 0; b < blocks.size(); ++b) {
    if (!open[b]) continue;
    Replay replay{blocks[b], settings, rough[b], none, std::nullopt};
    replay.run();
    stats.unsure += replay.unsure;
    if (!replay.ask) {
      open[b] = 0;
      continue;
    }
    requests.push_back({int32_t(b), *replay.ask});
    deepest.push_back({b, {}, *replay.ask});
  }
  const auto asked = [&](size_t b, Int3 ncp) {
    return std::any_of(requests.begin(), requests.end(),
                       [&](const LsqRequest& r) { return size_t(r.block) == b && r.ncp == ncp; });
  };
  while (!deepest.empty() && int64_t(requests.size()) < atOnce) {
    std::vector<Branch> next;
    for (const Branch& br : deepest)
      for (const bool passes : {true, false}) {
        if (int64_t(requests.size()) >= atOnce) break;
        Assumed assumed = br.assumed;
        assumed.emplace_back(br.ncp, passes);
        Replay replay{blocks[br.block], settings, rough[br.block], assumed, std::nullopt};
        replay.run();
        if (!replay.ask || asked(br.block, *replay.ask)) continue;
        requests.push_back({int32_t(br.block), *replay.ask});
        next.push_back({br.block, std::move(assumed), *replay.ask});
      }
    deepest = std::move(next);
  }
  return requests;
}

}  // namespace

Verdict lsqVerdict(const LsqResidual& r, int64_t count, double bound) {
  const double target = bound * bound * double(count);
  const double roundingOfSums = 1e-11 * r.squares, roundingOfPoints = 1e-7 * target;
  if (r.residual > target + roundingOfSums) return Verdict::Fails;
  if (r.residual < target - roundingOfSums - roundingOfPoints) return Verdict::Passes;
  return Verdict::Unknown;
}

AheadStats askAhead(LeastSquaresBatch& batch, const std::vector<AheadBlock>& blocks,
                    const SearchSettings& settings, int64_t atOnce, const LevelSampler* copy) {
  AheadStats stats;
  std::vector<const float*> samples;
  std::vector<Int3> shapes;
  VolumeBoxes boxes{copy, {}};
  for (const AheadBlock& b : blocks) {
    samples.push_back(b.samples);
    shapes.push_back(b.n);
    if (b.origin) boxes.origins.push_back(*b.origin);
    b.out->bound = settings.bound;
    b.out->known.clear();
  }
  const auto tUpload = std::chrono::steady_clock::now();
  if (copy && boxes.origins.size() == blocks.size())
    batch.setBlocksIn(boxes, samples, shapes, settings.degree);
  else
    batch.setBlocks(samples, shapes, settings.degree);
  stats.uploadSeconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - tUpload).count();
  if (atOnce <= 0) atOnce = batch.requestsAtOnce();
  std::vector<std::optional<std::array<double, 3>>> rough;
  for (const AheadBlock& b : blocks) rough.push_back(b.rough);
  std::vector<uint8_t> open(blocks.size(), 1);
  std::vector<LsqResidual> answers;
  for (;;) {
    const std::vector<LsqRequest> requests =
        roundRequests(blocks, settings, rough, open, atOnce, stats);
    if (requests.empty()) return stats;
    const auto t0 = std::chrono::steady_clock::now();
    batch.residuals(requests, answers);
    stats.residualSeconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ++stats.rounds;
    stats.requests += int64_t(requests.size());
    for (size_t r = 0; r < requests.size(); ++r) {
      const AheadBlock& b = blocks[size_t(requests[r].block)];
      const int64_t count = int64_t(b.n[0]) * b.n[1] * b.n[2];
      b.out->set(requests[r].ncp, lsqVerdict(answers[r], count, settings.bound));
    }
  }
}

}  // namespace afam
