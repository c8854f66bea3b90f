// SPDX-License-Identifier: BSD-3-Clause
#include "afam/search/least_squares_batch.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "afam/sampling/level_sampler.hpp"
#include "afam/search/least_squares_order.hpp"
#include "afam/spline/fit.hpp"

namespace afam {

std::vector<double> axisProjection(int n, int ncp, int degree) {
  const std::vector<double> values = collocationMatrix(n, ncp, degree);
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const Eigen::Map<const RowMajor> a(values.data(), n, ncp);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(a);
  const Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(n, ncp);
  std::vector<double> rows(size_t(ncp) * size_t(n));
  Eigen::Map<RowMajor>(rows.data(), ncp, n) = q.transpose();
  return rows;
}

uint64_t AxisProjections::offsetOf(int n, int ncp, int degree) {
  const auto key = std::make_tuple(n, ncp, degree);
  const auto found = offsets_.find(key);
  if (found != offsets_.end()) return found->second;
  const std::vector<double> rows = axisProjection(n, ncp, degree);
  const uint64_t at = values_.size();
  values_.insert(values_.end(), rows.begin(), rows.end());
  offsets_.emplace(key, at);
  return at;
}

void CpuLeastSquaresBatch::setBlocks(const std::vector<const float*>& samples,
                                     const std::vector<Int3>& n, int degree) {
  samples_ = samples;
  n_ = n;
  degree_ = degree;
}

void CpuLeastSquaresBatch::setBlocksIn(const VolumeBoxes& boxes,
                                       const std::vector<const float*>& samples,
                                       const std::vector<Int3>& n, int degree) {
  const auto* copy = dynamic_cast<const CpuLevelSampler*>(boxes.copy);
  if (!copy || boxes.origins.size() != n.size()) return setBlocks(samples, n, degree);
  gathered_.resize(n.size());
  std::vector<const float*> from(n.size());
  for (size_t b = 0; b < n.size(); ++b) {
    gathered_[b].resize(size_t(n[b][0]) * size_t(n[b][1]) * size_t(n[b][2]));
    copy->box(boxes.origins[b], n[b], gathered_[b].data());
    from[b] = gathered_[b].data();
  }
  setBlocks(from, n, degree);
}

void CpuLeastSquaresBatch::residuals(const std::vector<LsqRequest>& requests,
                                     std::vector<LsqResidual>& out) {
  out.assign(requests.size(), LsqResidual{});
  for (size_t r = 0; r < requests.size(); ++r) {
    const LsqRequest& q = requests[r];
    const Int3 n = n_.at(size_t(q.block)), k = q.ncp;
    uint64_t at[3];
    for (int a = 0; a < 3; ++a) at[a] = projections_.offsetOf(n[a], k[a], degree_);
    const double* rows[3];
    for (int a = 0; a < 3; ++a) rows[a] = projections_.values().data() + at[a];
    const LsqShape shape = lsqShape(n, k);
    afterY_.assign(size_t(shape.afterY), 0.0);
    centred_.resize(size_t(shape.plane));
    afterX_.resize(size_t(shape.afterX));
    const float* s = samples_[size_t(q.block)];
    double lanes[kLsqLanes];
    // The mean, then the squares about it, lane by lane as the GPU's threads sum them.
    std::fill(lanes, lanes + kLsqLanes, 0.0);
    for (int64_t z = 0; z < n[2]; ++z)
      for (int64_t e = 0; e < shape.plane; ++e)
        lanes[e % kLsqLanes] += double(s[z * shape.plane + e]);
    const double mean = lsqTreeSum(lanes) / double(shape.plane * n[2]);
    std::fill(lanes, lanes + kLsqLanes, 0.0);
    for (int64_t z = 0; z < n[2]; ++z) {
      for (int64_t e = 0; e < shape.plane; ++e) {
        const double d = double(s[z * shape.plane + e]) - mean;
        centred_[size_t(e)] = d;
        lanes[e % kLsqLanes] += d * d;
      }
      for (int64_t o = 0; o < shape.afterX; ++o)
        lsqAlongX<1>(rows[0], centred_.data(), n[0], n, o, 0, shape.afterX, &afterX_[size_t(o)]);
      for (int64_t o = 0; o < shape.slice; ++o)
        lsqAlongY<1>(rows[1], n[1], afterX_.data(), n, k, o, 0, shape.slice,
                     &afterY_[size_t(z * shape.slice + o)]);
    }
    const double squares = lsqTreeSum(lanes);
    std::fill(lanes, lanes + kLsqLanes, 0.0);
    for (int64_t j = 0; j < shape.slice; ++j)
      lanes[j % kLsqLanes] += lsqColumnEnergy<1>(rows[2], afterY_.data() + j, shape.slice, n, k);
    out[r] = {squares, squares - lsqTreeSum(lanes)};
  }
}

}  // namespace afam
