// SPDX-License-Identifier: BSD-3-Clause
// ForeCache (Battle, Chang, Stonebraker, SIGMOD 2016) for a 3D orbiting camera, run live.
//
// ForeCache combines two recommenders and switches between them by the user's analysis phase:
//  * actions-based (AB): an n-gram Markov chain over the user's recent moves predicts the next
//  move;
//  * signature-based (SB): recommends data whose statistical signature resembles the data the user
//    has recently dwelt on;
//  * a phase classifier over the recent moves (ForeCache: Foraging, Navigation, Sensemaking). The
//    paper uses AB while the user forages or navigates and SB while the user makes sense of a
//    region (small, back-and-forth moves). Ours is a rule classifier on the same move features
//    (speed, direction consistency, zoom, distance) instead of ForeCache's trained SVM.
//
// Moves: the step between two poses, in the tangent frame of the first one (e_theta, e_phi) in
// degrees, plus the change of distance, quantised to a symbol: stay, zoom in, zoom out, or one of
// 8 directions x 2 speeds. The displacement a symbol stands for is the running mean of the steps
// observed with it.
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "afam/scene/camera.hpp"

namespace afam {

enum class ForeCachePhase { Foraging, Navigation, Sensemaking };
const char* toString(ForeCachePhase phase);

struct ForeCacheOptions {
  int order = 3;              ///< Markov chain order (longest context), backs off to shorter ones
  double stayDegrees = 0.4;   ///< steps below this angle (and zoom) are "stay"
  double fastDegrees = 5.0;   ///< angle separating the two speed classes
  double zoomEpsilon = 0.02;  ///< |delta distance| that makes a pure-zoom move
  int phaseWindow = 6;        ///< moves the phase classifier looks at
  double sensemakingDegrees = 1.5;  ///< mean step below this (or no net progress): Sensemaking
  double consistency = 0.5;         ///< net / path length below this: wandering (Sensemaking)
  double foragingDistance = 1.6;    ///< far from the volume and moving: Foraging
};

/// A move between two poses in the first pose's tangent frame.
struct CameraMove {
  double dTheta = 0, dPhi = 0;  ///< degrees of arc along e_theta and e_phi
  double dDistance = 0;
};

class ForeCacheMarkov {
 public:
  static constexpr int kStay = 0, kZoomIn = 1, kZoomOut = 2, kFirstDirection = 3;
  static constexpr int kSymbols = kFirstDirection + 16;

  explicit ForeCacheMarkov(const ForeCacheOptions& options = {}) : opt_(options) {}
  void reset();
  static CameraMove moveBetween(const Pose& from, const Pose& to);
  static Pose applyMove(const Pose& from, const CameraMove& move);
  int symbolOf(const CameraMove& m) const;
  /// Learns from one more move (updates the n-gram counts and the symbol's mean displacement).
  void observeMove(const CameraMove& m);
  /// Most likely next symbol given the recent symbols (longest context with counts; ties go to the
  /// most recent symbol). Repeats the last symbol when nothing was learnt.
  int predictSymbol() const;
  /// Symbols ranked by probability for the current context (for prefetching several moves).
  std::vector<std::pair<int, double>> rankedSymbols() const;
  CameraMove meanMove(int symbol) const;
  const std::deque<int>& recentSymbols() const { return recent_; }

 private:
  ForeCacheOptions opt_;
  std::deque<int> recent_;
  std::map<std::vector<int>, std::array<uint32_t, kSymbols>> counts_;
  std::array<CameraMove, kSymbols> sum_{};
  std::array<uint32_t, kSymbols> n_{};
};

/// Phase of the user from the recent moves (most recent last).
ForeCachePhase classifyPhase(const std::deque<CameraMove>& moves, double currentDistance,
                             const ForeCacheOptions& options);

/// Data signature of a block: a few statistics from the .afam index.
using BlockSignature = std::array<float, 4>;

/// What the SB model needs from the data: the blocks a pose sees and each block's signature.
/// Without it ForeCache predicts with the AB model only in every phase but Sensemaking, where it
/// predicts the current pose (dwelling).
struct ForeCacheDataSource {
  std::function<std::vector<int64_t>(const Pose&)> visibleBlocks;  ///< block keys
  std::function<BlockSignature(int64_t)> signature;
};

/// ForeCache's model of the user over poses, the state behind the "forecache" predictor
/// (ForeCachePredictor, prefetch_predictors.hpp): AB (Markov) in Foraging/Navigation, SB in
/// Sensemaking: among the candidate next poses (one mean move of each learnt symbol), the one whose
/// visible blocks' mean signature is closest to the dwell signature (recency-weighted mean over
/// recent views).
class ForeCacheModel {
 public:
  explicit ForeCacheModel(const ForeCacheOptions& options = {}, ForeCacheDataSource data = {});
  /// Forget everything learnt (a new trajectory starts).
  void reset();
  /// The user is now at `pose` (called once per point of view, in order).
  void observe(const Pose& pose);
  /// The predicted next pose: the last pose until two were observed, a default Pose before any.
  Pose predictNext() const;
  ForeCachePhase phase() const { return phase_; }
  const ForeCacheMarkov& markov() const { return markov_; }
  /// Poses to prefetch for, best first (Markov's top moves, or the SB choice first in Sensemaking).
  std::vector<Pose> candidatePoses(int count) const;
  /// Blocks ranked by SB similarity among `candidates` (block keys), most similar first; empty
  /// without a data source or before any view.
  std::vector<int64_t> rankBySignature(const std::vector<int64_t>& candidates) const;

 private:
  Pose signaturePrediction() const;
  float signatureDistance(const std::vector<int64_t>& blocks) const;

  ForeCacheOptions opt_;
  ForeCacheDataSource data_;
  Pose last_{};
  uint64_t observed_ = 0;
  ForeCacheMarkov markov_;
  std::deque<CameraMove> moves_;
  ForeCachePhase phase_ = ForeCachePhase::Navigation;
  BlockSignature dwell_{};
  bool haveDwell_ = false;
};

}  // namespace afam
