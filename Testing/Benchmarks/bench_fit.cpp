// SPDX-License-Identifier: BSD-3-Clause
// Fit and evaluation speed of the B-spline core, each next to a baseline in the same run.
//
//   BM_FitBanded/ncp/p      our separable banded fit of a 64^3 Marschner-Lobb block, with the
//                           error on all 262,144 samples (the bar: NCP 32, p 2 <= 6 ms)
//   BM_FitBandedNoError     the same without the error pass (MFA's 0.056 s is without error)
//   BM_FitDenseBaseline     baseline: per axis a dense A (n x ncp), dense LLT of A^T A, and per
//   line
//                           a dense A^T d and a dense solve; dense per-axis evaluation for the
//                           error
//   BM_Evaluate / BM_EvaluateGradient   evaluateModel at random points, one thread (items/s)
//   BM_EvaluateBatch / BM_EvaluateGradientBatch   the same points through evaluateModelBatch,
//                           4 lanes (SSE2) and 8 lanes (AVX2, the default where the CPU has it)
//
// Run: build-core/Testing/Benchmarks/bench_fit --benchmark_repetitions=5
//        --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "afam/spline/basis.hpp"
#include "afam/spline/evaluate.hpp"
#include "afam/spline/evaluate_batch.hpp"
#include "afam/spline/fit.hpp"
#include "afam/volume/marschner_lobb.hpp"

namespace {

constexpr int kN = 64;

const std::vector<float>& mlBlock() {
  static const std::vector<float> block = [] {
    std::vector<float> b(size_t(kN) * kN * kN);
    afam::marschnerLobbSlab(afam::MarschnerLobb{}, {kN, kN, kN}, 0, kN, b.data());
    return b;
  }();
  return block;
}

void BM_FitBanded(benchmark::State& state) {
  const int ncp = int(state.range(0)), p = int(state.range(1));
  const bool withError = state.range(2) != 0;
  const auto& block = mlBlock();
  afam::BlockFitter fitter;
  afam::FitResult result;
  for (auto _ : state) {
    fitter.fitInto(block.data(), {kN, kN, kN}, {ncp, ncp, ncp}, p, withError, result);
    benchmark::DoNotOptimize(result.control.data());
    benchmark::ClobberMemory();
  }
  state.counters["rmse"] = result.error.rmse;
  state.SetItemsProcessed(state.iterations() * int64_t(block.size()));
}

// ---- Baseline: dense per-axis normal equations, one line at a time ----
struct DenseAxis {
  Eigen::MatrixXd a;  // n x ncp collocation
  Eigen::LLT<Eigen::MatrixXd> llt;
  DenseAxis(int n, int ncp, int p) : a(Eigen::MatrixXd::Zero(n, ncp)) {
    const afam::Knots k = afam::Knots::make(ncp, p);
    double basis[afam::kMaxOrder];
    for (int i = 0; i < n; ++i) {
      const double u = double(i) / double(n - 1);
      const int s = k.span(u);
      afam::basisFunctions<double>(k, s, u, basis);
      for (int r = 0; r <= p; ++r) a(i, s - p + r) = basis[r];
    }
    llt.compute(a.transpose() * a);
  }
};

/// Fits along one axis of `in` (dims d, x fastest) into `out` where that axis becomes m long.
void denseAxisPass(const DenseAxis& ax, const std::vector<double>& in, std::array<int, 3> d,
                   int axis, std::vector<double>& out) {
  const int m = int(ax.a.cols());
  std::array<int, 3> od = d;
  od[axis] = m;
  out.assign(size_t(od[0]) * od[1] * od[2], 0.0);
  const size_t stride[3] = {1, size_t(d[0]), size_t(d[0]) * d[1]};
  const size_t ostride[3] = {1, size_t(od[0]), size_t(od[0]) * od[1]};
  const int o1 = (axis + 1) % 3, o2 = (axis + 2) % 3;
  Eigen::VectorXd line(d[axis]), coef(m);
  for (int j = 0; j < d[o2]; ++j)
    for (int i = 0; i < d[o1]; ++i) {
      const size_t base = size_t(i) * stride[o1] + size_t(j) * stride[o2];
      const size_t obase = size_t(i) * ostride[o1] + size_t(j) * ostride[o2];
      for (int k = 0; k < d[axis]; ++k) line(k) = in[base + size_t(k) * stride[axis]];
      coef = ax.llt.solve(ax.a.transpose() * line);
      for (int k = 0; k < m; ++k) out[obase + size_t(k) * ostride[axis]] = coef(k);
    }
}

void denseEvalPass(const DenseAxis& ax, const std::vector<double>& in, std::array<int, 3> d,
                   int axis, std::vector<double>& out) {
  const int n = int(ax.a.rows());
  std::array<int, 3> od = d;
  od[axis] = n;
  out.assign(size_t(od[0]) * od[1] * od[2], 0.0);
  const size_t stride[3] = {1, size_t(d[0]), size_t(d[0]) * d[1]};
  const size_t ostride[3] = {1, size_t(od[0]), size_t(od[0]) * od[1]};
  const int o1 = (axis + 1) % 3, o2 = (axis + 2) % 3;
  Eigen::VectorXd line(d[axis]), values(n);
  for (int j = 0; j < d[o2]; ++j)
    for (int i = 0; i < d[o1]; ++i) {
      const size_t base = size_t(i) * stride[o1] + size_t(j) * stride[o2];
      const size_t obase = size_t(i) * ostride[o1] + size_t(j) * ostride[o2];
      for (int k = 0; k < d[axis]; ++k) line(k) = in[base + size_t(k) * stride[axis]];
      values = ax.a * line;
      for (int k = 0; k < n; ++k) out[obase + size_t(k) * ostride[axis]] = values(k);
    }
}

void BM_FitDenseBaseline(benchmark::State& state) {
  const int ncp = int(state.range(0)), p = int(state.range(1));
  const auto& block = mlBlock();
  const std::vector<double> data(block.begin(), block.end());
  double rmse = 0;
  std::vector<double> t1, t2, t3, e1, e2, e3;
  std::vector<float> control;
  for (auto _ : state) {
    // The factorisation is part of the work, as it is for ours (cached there across calls).
    DenseAxis ax(kN, ncp, p);
    denseAxisPass(ax, data, {kN, kN, kN}, 0, t1);
    denseAxisPass(ax, t1, {ncp, kN, kN}, 1, t2);
    denseAxisPass(ax, t2, {ncp, ncp, kN}, 2, t3);
    control.assign(t3.begin(), t3.end());
    const std::vector<double> c(control.begin(), control.end());
    denseEvalPass(ax, c, {ncp, ncp, ncp}, 0, e1);
    denseEvalPass(ax, e1, {kN, ncp, ncp}, 1, e2);
    denseEvalPass(ax, e2, {kN, kN, ncp}, 2, e3);
    double sum = 0;
    for (size_t i = 0; i < e3.size(); ++i) sum += (e3[i] - data[i]) * (e3[i] - data[i]);
    rmse = std::sqrt(sum / double(e3.size()));
    benchmark::DoNotOptimize(rmse);
  }
  state.counters["rmse"] = rmse;
  state.SetItemsProcessed(state.iterations() * int64_t(block.size()));
}

constexpr int kPoints = 1 << 16;

/// The evaluation benchmarks' model (the ML block fitted at ncp = range(0), p = range(1)) and
/// kPoints random parameter triples.
struct EvaluationCase {
  afam::FitResult model;
  std::vector<float> uvw;
  explicit EvaluationCase(const benchmark::State& state) : uvw(3 * kPoints) {
    const int ncp = int(state.range(0)), p = int(state.range(1));
    afam::BlockFitter fitter;
    model = fitter.fit(mlBlock().data(), {kN, kN, kN}, {ncp, ncp, ncp}, p, false);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> uni(0.f, 1.f);
    for (auto& x : uvw) x = uni(rng);
  }
};

template <bool WithGradient>
void BM_EvaluateT(benchmark::State& state) {
  const EvaluationCase c(state);
  const afam::ModelView view = c.model.view();
  const std::vector<float>& uvw = c.uvw;
  for (auto _ : state) {
    float acc = 0.f;
    float g[3];
    for (int i = 0; i < kPoints; ++i) {
      acc += afam::evaluateModel<WithGradient>(view, uvw[3 * i], uvw[3 * i + 1], uvw[3 * i + 2],
                                               WithGradient ? g : nullptr);
      if (WithGradient) acc += g[0] + g[1] + g[2];
    }
    benchmark::DoNotOptimize(acc);
  }
  state.SetItemsProcessed(state.iterations() * kPoints);
}

/// The same points and model through evaluateModelBatch (bitwise equal results), with the SIMD
/// width range(2): 4 lanes (baseline x86-64) or 8 (AVX2, what evaluateModelBatch picks there).
template <bool WithGradient>
void BM_EvaluateBatchT(benchmark::State& state) {
  const int lanes = int(state.range(2));
  if (lanes > afam::detail::batchLanes()) {
    state.SkipWithError("this CPU has no AVX2");
    return;
  }
  const EvaluationCase c(state);
  const afam::ModelView view = c.model.view();
  const std::vector<float>& uvw = c.uvw;
  std::vector<float> value(kPoints), gradient(WithGradient ? 3 * kPoints : 0);
  for (auto _ : state) {
    afam::detail::evaluateModelBatchLanes(lanes, view, uvw.data(), kPoints, value.data(),
                                          WithGradient ? gradient.data() : nullptr);
    benchmark::DoNotOptimize(value.data());
    benchmark::DoNotOptimize(gradient.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * kPoints);
}

}  // namespace

BENCHMARK(BM_FitBanded)
    ->ArgNames({"ncp", "p", "err"})
    ->ArgsProduct({{8, 16, 32, 64}, {2, 3}, {1}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FitBanded)
    ->Name("BM_FitBandedNoError")
    ->ArgNames({"ncp", "p", "err"})
    ->Args({32, 2, 0})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FitDenseBaseline)
    ->ArgNames({"ncp", "p"})
    ->ArgsProduct({{8, 16, 32, 64}, {2, 3}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_EvaluateT, false)
    ->Name("BM_Evaluate")
    ->ArgNames({"ncp", "p"})
    ->Args({32, 2})
    ->Args({32, 3});
BENCHMARK_TEMPLATE(BM_EvaluateT, true)
    ->Name("BM_EvaluateGradient")
    ->ArgNames({"ncp", "p"})
    ->Args({32, 2})
    ->Args({32, 3});
BENCHMARK_TEMPLATE(BM_EvaluateBatchT, false)
    ->Name("BM_EvaluateBatch")
    ->ArgNames({"ncp", "p", "lanes"})
    ->ArgsProduct({{32}, {2}, {4, 8}});
BENCHMARK_TEMPLATE(BM_EvaluateBatchT, true)
    ->Name("BM_EvaluateGradientBatch")
    ->ArgNames({"ncp", "p", "lanes"})
    ->ArgsProduct({{32}, {2}, {4, 8}});

BENCHMARK_MAIN();
