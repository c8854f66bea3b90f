// SPDX-License-Identifier: BSD-3-Clause
#include "afam/predict/forecache.hpp"

#include <algorithm>
#include <cmath>

namespace afam {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

struct Frame {
  Vec3 u, eT, eP;
};
Frame frameOf(const Pose& p) {
  const double t = p.thetaDeg * kDeg, f = p.phiDeg * kDeg;
  return {{std::sin(t) * std::cos(f), std::sin(t) * std::sin(f), std::cos(t)},
          {std::cos(t) * std::cos(f), std::cos(t) * std::sin(f), -std::sin(t)},
          {-std::sin(f), std::cos(f), 0.0}};
}
double emaAlpha = 0.5;  // weight of the newest move in a symbol's displacement
}  // namespace

const char* toString(ForeCachePhase phase) {
  switch (phase) {
    case ForeCachePhase::Foraging:
      return "foraging";
    case ForeCachePhase::Navigation:
      return "navigation";
    case ForeCachePhase::Sensemaking:
      return "sensemaking";
  }
  return "?";
}

// ---------------------------------------------------------------------------------- Markov (AB)

void ForeCacheMarkov::reset() {
  recent_.clear();
  counts_.clear();
  sum_ = {};
  n_ = {};
}

CameraMove ForeCacheMarkov::moveBetween(const Pose& from, const Pose& to) {
  const Frame a = frameOf(from), b = frameOf(to);
  CameraMove m;
  m.dDistance = to.distance - from.distance;
  const double c = std::fmax(-1.0, std::fmin(1.0, dot(a.u, b.u)));
  const double ang = std::acos(c) / kDeg;
  Vec3 w{b.u[0] - c * a.u[0], b.u[1] - c * a.u[1], b.u[2] - c * a.u[2]};
  const double x = dot(w, a.eT), y = dot(w, a.eP), len = std::hypot(x, y);
  if (len > 1e-12) {
    m.dTheta = ang * x / len;
    m.dPhi = ang * y / len;
  }
  return m;
}

Pose ForeCacheMarkov::applyMove(const Pose& from, const CameraMove& m) {
  const Frame a = frameOf(from);
  const double ang = std::hypot(m.dTheta, m.dPhi);
  Vec3 u = a.u;
  if (ang > 1e-9) {
    const double s = std::sin(ang * kDeg), c = std::cos(ang * kDeg);
    for (int k = 0; k < 3; ++k)
      u[k] = c * a.u[k] + s * (m.dTheta * a.eT[k] + m.dPhi * a.eP[k]) / ang;
  }
  const double d = std::fmax(1e-3, from.distance + m.dDistance);
  Pose p = poseFromPosition({d * u[0], d * u[1], d * u[2]});
  return p;
}

int ForeCacheMarkov::symbolOf(const CameraMove& m) const {
  const double ang = std::hypot(m.dTheta, m.dPhi);
  if (ang < opt_.stayDegrees) {
    if (m.dDistance < -opt_.zoomEpsilon) return kZoomIn;
    if (m.dDistance > opt_.zoomEpsilon) return kZoomOut;
    return kStay;
  }
  double a = std::atan2(m.dPhi, m.dTheta) / (kPi / 4);  // sectors of 45 degrees
  int sector = static_cast<int>(std::lround(a)) % 8;
  if (sector < 0) sector += 8;
  const int fast = ang >= opt_.fastDegrees ? 1 : 0;
  return kFirstDirection + 2 * sector + fast;
}

void ForeCacheMarkov::observeMove(const CameraMove& m) {
  const int s = symbolOf(m);
  const int maxK = std::min<int>(opt_.order, static_cast<int>(recent_.size()));
  for (int k = 0; k <= maxK; ++k) {
    std::vector<int> ctx(recent_.end() - k, recent_.end());
    auto& row = counts_[ctx];
    ++row[s];
  }
  recent_.push_back(s);
  while (static_cast<int>(recent_.size()) > std::max(opt_.order, 1)) recent_.pop_front();
  if (n_[s] == 0) {
    sum_[s] = m;
  } else {
    sum_[s].dTheta += emaAlpha * (m.dTheta - sum_[s].dTheta);
    sum_[s].dPhi += emaAlpha * (m.dPhi - sum_[s].dPhi);
    sum_[s].dDistance += emaAlpha * (m.dDistance - sum_[s].dDistance);
  }
  ++n_[s];
}

std::vector<std::pair<int, double>> ForeCacheMarkov::rankedSymbols() const {
  const int maxK = std::min<int>(opt_.order, static_cast<int>(recent_.size()));
  const int last = recent_.empty() ? kStay : recent_.back();
  for (int k = maxK; k >= 0; --k) {
    std::vector<int> ctx(recent_.end() - k, recent_.end());
    auto it = counts_.find(ctx);
    if (it == counts_.end()) continue;
    double total = 0;
    for (uint32_t c : it->second) total += c;
    if (total <= 0) continue;
    std::vector<std::pair<int, double>> r;
    for (int s = 0; s < kSymbols; ++s)
      if (it->second[s]) r.emplace_back(s, it->second[s] / total);
    std::stable_sort(r.begin(), r.end(), [last](const auto& a, const auto& b) {
      if (a.second != b.second) return a.second > b.second;
      return (a.first == last) > (b.first == last);  // ties: keep doing what the user does
    });
    return r;
  }
  return {{last, 1.0}};
}

int ForeCacheMarkov::predictSymbol() const { return rankedSymbols().front().first; }

CameraMove ForeCacheMarkov::meanMove(int s) const {
  if (s >= 0 && s < kSymbols && n_[s]) return sum_[s];
  CameraMove m;  // nominal move of an unseen symbol
  if (s == kZoomIn) m.dDistance = -0.05;
  if (s == kZoomOut) m.dDistance = 0.05;
  if (s >= kFirstDirection && s < kSymbols) {
    const int sector = (s - kFirstDirection) / 2, fast = (s - kFirstDirection) % 2;
    const double ang = fast ? 7.0 : 3.0, dir = sector * kPi / 4;
    m.dTheta = ang * std::cos(dir);
    m.dPhi = ang * std::sin(dir);
  }
  return m;
}

// ------------------------------------------------------------------------------------- phases

ForeCachePhase classifyPhase(const std::deque<CameraMove>& moves, double currentDistance,
                             const ForeCacheOptions& o) {
  if (moves.empty()) return ForeCachePhase::Navigation;
  const int n = std::min<int>(o.phaseWindow, static_cast<int>(moves.size()));
  double path = 0, sx = 0, sy = 0, zoom = 0;
  for (int i = static_cast<int>(moves.size()) - n; i < static_cast<int>(moves.size()); ++i) {
    const CameraMove& m = moves[i];
    path += std::hypot(m.dTheta, m.dPhi);
    sx += m.dTheta;
    sy += m.dPhi;
    zoom += std::fabs(m.dDistance);
  }
  const double meanStep = path / n;
  const double consistency = path > 1e-9 ? std::hypot(sx, sy) / path : 0.0;
  // Zooming is navigation (the user is moving towards or away from something).
  if (zoom / n > o.zoomEpsilon && meanStep < o.sensemakingDegrees)
    return ForeCachePhase::Navigation;
  if (meanStep < o.sensemakingDegrees || consistency < o.consistency)
    return ForeCachePhase::Sensemaking;
  if (currentDistance >= o.foragingDistance) return ForeCachePhase::Foraging;
  return ForeCachePhase::Navigation;
}

// ------------------------------------------------------------------------------------- model

ForeCacheModel::ForeCacheModel(const ForeCacheOptions& options, ForeCacheDataSource data)
    : opt_(options), data_(std::move(data)), markov_(options) {}

void ForeCacheModel::reset() {
  last_ = Pose{};
  observed_ = 0;
  markov_.reset();
  moves_.clear();
  phase_ = ForeCachePhase::Navigation;
  haveDwell_ = false;
  dwell_ = {};
}

void ForeCacheModel::observe(const Pose& pose) {
  if (observed_ > 0) {
    const CameraMove m = ForeCacheMarkov::moveBetween(last_, pose);
    markov_.observeMove(m);
    moves_.push_back(m);
    while (static_cast<int>(moves_.size()) > std::max(opt_.phaseWindow, 1)) moves_.pop_front();
  }
  last_ = pose;
  ++observed_;
  phase_ = classifyPhase(moves_, pose.distance, opt_);
  if (data_.visibleBlocks && data_.signature) {
    const std::vector<int64_t> blocks = data_.visibleBlocks(pose);
    if (!blocks.empty()) {
      BlockSignature mean{};
      for (int64_t b : blocks) {
        const BlockSignature s = data_.signature(b);
        for (int k = 0; k < 4; ++k) mean[k] += s[k];
      }
      for (float& v : mean) v /= static_cast<float>(blocks.size());
      if (!haveDwell_) {
        dwell_ = mean;
        haveDwell_ = true;
      } else {
        for (int k = 0; k < 4; ++k) dwell_[k] = 0.7f * dwell_[k] + 0.3f * mean[k];
      }
    }
  }
}

float ForeCacheModel::signatureDistance(const std::vector<int64_t>& blocks) const {
  if (blocks.empty()) return 1e30f;
  BlockSignature mean{};
  for (int64_t b : blocks) {
    const BlockSignature s = data_.signature(b);
    for (int k = 0; k < 4; ++k) mean[k] += s[k];
  }
  float d = 0;
  for (int k = 0; k < 4; ++k) {
    const float x = mean[k] / static_cast<float>(blocks.size()) - dwell_[k];
    d += x * x;
  }
  return d;
}

Pose ForeCacheModel::signaturePrediction() const {
  const Pose& cur = last_;
  const auto ranked = markov_.rankedSymbols();
  Pose best = ForeCacheMarkov::applyMove(cur, markov_.meanMove(ranked.front().first));
  if (!(data_.visibleBlocks && data_.signature && haveDwell_)) return best;
  float bestD = signatureDistance(data_.visibleBlocks(best));
  const int limit = std::min<int>(4, static_cast<int>(ranked.size()));
  for (int i = 1; i <= limit; ++i) {
    const Pose cand = i < limit ? ForeCacheMarkov::applyMove(cur, markov_.meanMove(ranked[i].first))
                                : cur;  // last candidate: stay
    const float d = signatureDistance(data_.visibleBlocks(cand));
    if (d < bestD) {
      bestD = d;
      best = cand;
    }
  }
  return best;
}

Pose ForeCacheModel::predictNext() const {
  if (observed_ < 2) return last_;
  if (phase_ == ForeCachePhase::Sensemaking) return signaturePrediction();
  return ForeCacheMarkov::applyMove(last_, markov_.meanMove(markov_.predictSymbol()));
}

std::vector<Pose> ForeCacheModel::candidatePoses(int count) const {
  std::vector<Pose> out;
  if (observed_ == 0 || count <= 0) return out;
  out.push_back(predictNext());
  const auto ranked = markov_.rankedSymbols();
  for (const auto& [s, prob] : ranked) {
    if (static_cast<int>(out.size()) >= count) break;
    (void)prob;
    Pose p = ForeCacheMarkov::applyMove(last_, markov_.meanMove(s));
    if (poseDistance(p, out.front()) > 1e-6) out.push_back(p);
  }
  return out;
}

std::vector<int64_t> ForeCacheModel::rankBySignature(const std::vector<int64_t>& candidates) const {
  if (!(data_.signature && haveDwell_)) return {};
  std::vector<std::pair<float, int64_t>> scored;
  scored.reserve(candidates.size());
  for (int64_t b : candidates) {
    const BlockSignature s = data_.signature(b);
    float d = 0;
    for (int k = 0; k < 4; ++k) d += (s[k] - dwell_[k]) * (s[k] - dwell_[k]);
    scored.emplace_back(d, b);
  }
  std::stable_sort(scored.begin(), scored.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<int64_t> out;
  out.reserve(scored.size());
  for (const auto& e : scored) out.push_back(e.second);
  return out;
}

}  // namespace afam
