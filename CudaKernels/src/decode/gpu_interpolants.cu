// SPDX-License-Identifier: BSD-3-Clause
// GpuInterpolants (gpu_interpolants.hpp). Compiled with -fmad=false: interpolation_passes.hpp's
// products and sums, and roundedPoint's, round as they do on the CPU.
#include "decode/gpu_interpolants.hpp"

#include <cuda_runtime.h>

#include <algorithm>
#include <cstring>

#include "afam/entropy/lanes_coder.hpp"
#include "afam/format/block_codec.hpp"
#include "afam/format/rounded_points.hpp"
#include "afam/format/value_prediction.hpp"
#include "afam/spline/fit.hpp"
#include "common/cuda_check.hpp"

namespace afam {

namespace {

constexpr int kLineThreads = 128;
constexpr unsigned kMaxGroupJobs = 65535;  // a grid's y extent
constexpr unsigned kFinishBlocks = 64;     // blocks a job's points are spread over, at most

size_t alignUp(size_t v, size_t a) { return (v + a - 1) / a * a; }

__device__ InterpolationAxisView axisView(const GpuAxisRef& r, const unsigned char* area) {
  InterpolationAxisView v;
  v.n = r.n;
  v.p = r.p;
  v.rowFirst = reinterpret_cast<const int*>(area + r.rowFirst);
  v.rowLast = reinterpret_cast<const int*>(area + r.rowLast);
  v.columnOffset = reinterpret_cast<const int*>(area + r.columnOffset);
  v.columnWeight = reinterpret_cast<const double*>(area + r.columnWeight);
  v.lower = reinterpret_cast<const double*>(area + r.lower);
  v.invDiag = reinterpret_cast<const double*>(area + r.invDiag);
  return v;
}

__device__ __forceinline__ Int3 samplesOf(const GpuDecodeJob& job) {
  return Int3{job.ncp[0], job.ncp[1], job.ncp[2]};
}

__device__ __forceinline__ uint64_t pointsOf(const GpuDecodeJob& job) {
  return uint64_t(uint32_t(job.ncp[0])) * uint32_t(job.ncp[1]) * uint32_t(job.ncp[2]);
}

/// One pass, a thread a line, a row of blocks (grid y) a job of the group.
__global__ void __launch_bounds__(kLineThreads)
    interpolationPassKernel(InterpolationPass pass, const GpuDecodeJob* __restrict__ jobs,
                            const GpuInterpolantJob* __restrict__ group,
                            const GpuAxisRef* __restrict__ refs, const unsigned char* area,
                            float* output, double* scratch, const uint32_t* __restrict__ status) {
  const GpuInterpolantJob ij = group[blockIdx.y];
  if (status[ij.job]) return;  // its samples did not decode
  const GpuDecodeJob& job = jobs[ij.job];
  const Int3 n = samplesOf(job);
  const int64_t line = int64_t(blockIdx.x) * kLineThreads + threadIdx.x;
  if (line >= interpolationLines(pass, n)) return;
  const InterpolationAxisView axes[3] = {axisView(refs[ij.axis[0]], area),
                                         axisView(refs[ij.axis[1]], area),
                                         axisView(refs[ij.axis[2]], area)};
  double* a = scratch + ij.scratchOffset;
  interpolationPassLine(pass, axes, n, line, output + job.outputOffset, a, a + pointsOf(job));
}

/// The control points into the job's output: float32 of the solution, refused where infinite
/// (the fitter's overflow check), rounded to the job's step where it has one.
__global__ void __launch_bounds__(kLineThreads)
    interpolationFinishKernel(const GpuDecodeJob* __restrict__ jobs,
                              const GpuInterpolantJob* __restrict__ group, float* output,
                              const double* scratch, uint32_t* status) {
  const GpuInterpolantJob ij = group[blockIdx.y];
  if (status[ij.job]) return;
  const GpuDecodeJob& job = jobs[ij.job];
  const uint64_t count = pointsOf(job);
  const double* a = scratch + ij.scratchOffset;
  float* out = output + job.outputOffset;
  bool ok = true;
  for (uint64_t i = uint64_t(blockIdx.x) * kLineThreads + threadIdx.x; i < count;
       i += uint64_t(gridDim.x) * kLineThreads) {
    const float c = __double2float_rn(a[i]);
    float value = c;
    ok &= !isinf(c);
    if (job.pointStep > 0) {
      double code;
      ok &= roundedPoint(c, job.pointStep, job.pointInverse, &value, &code);
    }
    out[i] = value;
  }
  if (!ok) status[ij.job] = uint32_t(GpuDecodeStatus::Interpolation);
}

constexpr int kPredictThreads = 512;

/// Points of the sub-lattice x0 + i s2 (i >= 0, < n) along an axis of n samples.
__device__ __forceinline__ int64_t along(int n, int x0, int s2) {
  return x0 < n ? (n - 1 - x0) / s2 + 1 : 0;
}

/// One step of the interpolation predictor at spacing s: the points x0 + i sx2, y0 + j sy2,
/// z0 + k sz2 (in the CPU's z, y, x order, from residual `base`) predicted along `axis`.
__device__ void predictStep(const codec::Lattice& L, int s, int axis, const int32_t* codes,
                            int64_t base, double step, double* q) {
  const int s2 = 2 * s;
  const int x0 = axis == 0 ? s : 0, y0 = axis == 1 ? s : 0, z0 = axis == 2 ? s : 0;
  const int sx = axis == 0 ? s2 : s, sy = axis == 0 ? s2 : axis == 1 ? s2 : s, sz = s2;
  const int zs = axis == 2 ? s2 : sz;
  const int64_t cx = along(L.n[0], x0, sx), cy = along(L.n[1], y0, sy), cz = along(L.n[2], z0, zs);
  const int64_t strideY = L.n[0], strideZ = int64_t(L.n[0]) * L.n[1];
  for (int64_t t = threadIdx.x; t < cx * cy * cz; t += kPredictThreads) {
    const int x = x0 + int(t % cx) * sx, y = y0 + int((t / cx) % cy) * sy,
              z = z0 + int(t / (cx * cy)) * zs;
    const int64_t i = L.index(x, y, z);
    const double pred = axis == 0 ? codec::interpolate(x, s, L.n[0], q + L.index(0, y, z), 1)
                        : axis == 1
                            ? codec::interpolate(y, s, L.n[1], q + L.index(0, 0, z) + x, strideY)
                            : codec::interpolate(z, s, L.n[2], q + L.index(0, y, 0) + x, strideZ);
    q[i] = pred + double(codes[base + t]) * step;
  }
}

/// Points visited by a step (predictStep's count).
__device__ int64_t stepPoints(const codec::Lattice& L, int s, int axis) {
  const int s2 = 2 * s;
  const int x0 = axis == 0 ? s : 0, y0 = axis == 1 ? s : 0, z0 = axis == 2 ? s : 0;
  const int sx = axis == 0 ? s2 : s, sy = axis == 0 ? s2 : axis == 1 ? s2 : s;
  const int zs = s2;
  return along(L.n[0], x0, sx) * along(L.n[1], y0, sy) * along(L.n[2], z0, zs);
}

/// A block a job: the samples of a job in the double interpolation form from the residuals the
/// parse left in its output (int32 each, in the CPU's visiting order): Lorenzo on the coarsest
/// lattice (one thread: a handful of points), then every spacing's steps along x, y and z, the
/// points of a step at once; then the samples, as float32, into the output (NotFinite where the
/// CPU refuses one).
__global__ void __launch_bounds__(kPredictThreads)
    predictionKernel(const GpuDecodeJob* __restrict__ jobs,
                     const GpuInterpolantJob* __restrict__ group, const uint8_t* payloads,
                     float* output, double* scratch, uint32_t* status) {
  const GpuInterpolantJob ij = group[blockIdx.x];
  const GpuDecodeJob& job = jobs[ij.job];
  if (!gpuJobInDoubleForm(job) || status[ij.job]) return;
  const codec::Lattice L{samplesOf(job)};
  const uint64_t count = pointsOf(job);
  double* q = scratch + ij.scratchOffset + count;  // the passes' second buffer, free until then
  const int32_t* codes = reinterpret_cast<const int32_t*>(output + job.outputOffset);
  const uint8_t* p = payloads + job.payloadOffset;
  const double step = __longlong_as_double(
      (long long)(uint64_t(lanes::readU32(p)) | uint64_t(lanes::readU32(p + 4)) << 32));
  const int S = codec::coarsestSpacing(L.n);
  if (threadIdx.x == 0) {
    int64_t c = 0;
    codec::lorenzo(L, q, S,
                   [&](int64_t i, double pred) { q[i] = pred + double(codes[c++]) * step; });
  }
  int64_t base = along(L.n[0], 0, S) * along(L.n[1], 0, S) * along(L.n[2], 0, S);
  __syncthreads();
  for (int s = S / 2; s >= 1; s /= 2)
    for (int axis = 0; axis < 3; ++axis) {
      predictStep(L, s, axis, codes, base, step, q);
      base += stepPoints(L, s, axis);
      __syncthreads();
    }
  bool infinite = false;
  for (uint64_t i = threadIdx.x; i < count; i += kPredictThreads) {
    const float v = __double2float_rn(q[i]);
    infinite |= !isfinite(v);
    output[job.outputOffset + i] = v;
  }
  if (__syncthreads_or(infinite) && threadIdx.x == 0)
    status[ij.job] = uint32_t(GpuDecodeStatus::NotFinite);
}

}  // namespace

uint32_t GpuInterpolants::axisIndex(int n, int p) {
  const std::pair<int, int> key{n, p};
  const auto at = std::find(batchAxes_.begin(), batchAxes_.end(), key);
  if (at != batchAxes_.end()) return uint32_t(at - batchAxes_.begin());
  if (!axes_.count(key)) axes_.emplace(key, interpolationAxis(n, p));
  batchAxes_.push_back(key);
  return uint32_t(batchAxes_.size() - 1);
}

bool GpuInterpolants::upload(const std::vector<GpuDecodeJob>& jobs, void* streamArg) {
  list_.clear();
  groups_.clear();
  batchAxes_.clear();
  scratchNeeded_ = 0;
  const uint64_t groupLimit = kGroupScratchBytes / sizeof(double);
  uint64_t groupNeed = 0;
  for (size_t i = 0; i < jobs.size(); ++i) {
    const GpuDecodeJob& j = jobs[i];
    if (j.kind != GpuDecodeKind::Interpolant) continue;
    GpuInterpolantJob ij;
    ij.job = uint32_t(i);
    for (int a = 0; a < 3; ++a) ij.axis[a] = axisIndex(j.ncp[a], j.degree[a]);
    const Int3 n{j.ncp[0], j.ncp[1], j.ncp[2]};
    const uint64_t points = uint64_t(n[0]) * uint64_t(n[1]) * uint64_t(n[2]);
    if (groups_.empty() || groups_.back().count >= kMaxGroupJobs ||
        (groupNeed + 2 * points > groupLimit && groups_.back().count > 0)) {
      groups_.push_back(Group{list_.size(), 0, 0, 0});
      groupNeed = 0;
    }
    Group& g = groups_.back();
    ij.scratchOffset = groupNeed;
    groupNeed += 2 * points;
    scratchNeeded_ = std::max(scratchNeeded_, groupNeed);
    g.count++;
    g.points = std::max(g.points, points);
    for (int p = 0; p < kInterpolationPasses; ++p)
      g.lines = std::max(g.lines, interpolationLines(InterpolationPass(p), n));
    list_.push_back(ij);
  }
  if (list_.empty()) return false;
  // The axis area: each system's arrays, 8-byte aligned; then the refs and jobs before it.
  std::vector<GpuAxisRef> refs;
  size_t area = 0;
  auto place = [&area](size_t bytes) {
    const size_t at = area;
    area = alignUp(area + bytes, 8);
    return uint32_t(at);
  };
  for (const auto& key : batchAxes_) {
    const InterpolationAxis& s = axes_.at(key);
    GpuAxisRef r;
    r.n = s.n;
    r.p = s.p;
    r.rowFirst = place(s.rowFirst.size() * sizeof(int));
    r.rowLast = place(s.rowLast.size() * sizeof(int));
    r.columnOffset = place(s.columnOffset.size() * sizeof(int));
    r.columnWeight = place(s.columnWeight.size() * sizeof(double));
    r.lower = place(s.lower.size() * sizeof(double));
    r.invDiag = place(s.invDiag.size() * sizeof(double));
    refs.push_back(r);
  }
  jobsAt_ = alignUp(refs.size() * sizeof(GpuAxisRef), 16);
  areaAt_ = alignUp(jobsAt_ + list_.size() * sizeof(GpuInterpolantJob), 16);
  const size_t total = areaAt_ + area;
  if (total > stagingCapacity_) {
    if (staging_) AFAM_CUDA_CHECK(cudaFreeHost(staging_));
    staging_ = nullptr;
    stagingCapacity_ = 0;
    void* raw = nullptr;
    AFAM_CUDA_CHECK(cudaMallocHost(&raw, total));
    staging_ = static_cast<unsigned char*>(raw);
    stagingCapacity_ = total;
  }
  const auto grow = [](auto*& p, size_t& capacity, size_t bytes) {
    if (bytes <= capacity) return;
    const size_t want = std::max(bytes, capacity + capacity / 2);
    if (p) AFAM_CUDA_CHECK(cudaFree(p));
    p = nullptr;
    capacity = 0;
    void* raw = nullptr;
    AFAM_CUDA_CHECK(cudaMalloc(&raw, want));
    p = static_cast<std::remove_reference_t<decltype(p)>>(raw);
    capacity = want;
  };
  grow(tables_, tablesCapacity_, total);
  grow(scratch_, scratchCapacity_, scratchNeeded_ * sizeof(double));
  std::memcpy(staging_, refs.data(), refs.size() * sizeof(GpuAxisRef));
  std::memcpy(staging_ + jobsAt_, list_.data(), list_.size() * sizeof(GpuInterpolantJob));
  unsigned char* out = staging_ + areaAt_;
  for (size_t k = 0; k < batchAxes_.size(); ++k) {
    const InterpolationAxis& s = axes_.at(batchAxes_[k]);
    const GpuAxisRef& r = refs[k];
    std::memcpy(out + r.rowFirst, s.rowFirst.data(), s.rowFirst.size() * sizeof(int));
    std::memcpy(out + r.rowLast, s.rowLast.data(), s.rowLast.size() * sizeof(int));
    std::memcpy(out + r.columnOffset, s.columnOffset.data(), s.columnOffset.size() * sizeof(int));
    std::memcpy(out + r.columnWeight, s.columnWeight.data(),
                s.columnWeight.size() * sizeof(double));
    std::memcpy(out + r.lower, s.lower.data(), s.lower.size() * sizeof(double));
    std::memcpy(out + r.invDiag, s.invDiag.data(), s.invDiag.size() * sizeof(double));
  }
  AFAM_CUDA_CHECK(cudaMemcpyAsync(tables_, staging_, total, cudaMemcpyHostToDevice,
                                  static_cast<cudaStream_t>(streamArg)));
  return true;
}

void GpuInterpolants::launch(const GpuDecodeJob* jobs, const uint8_t* payloads, float* output,
                             uint32_t* status, void* streamArg) {
  const auto stream = static_cast<cudaStream_t>(streamArg);
  const auto* refs = reinterpret_cast<const GpuAxisRef*>(tables_);
  const auto* list = reinterpret_cast<const GpuInterpolantJob*>(tables_ + jobsAt_);
  const unsigned char* area = tables_ + areaAt_;
  for (const Group& g : groups_) {
    predictionKernel<<<unsigned(g.count), kPredictThreads, 0, stream>>>(
        jobs, list + g.first, payloads, output, scratch_, status);
    AFAM_CUDA_CHECK(cudaGetLastError());
    const dim3 lines(unsigned((g.lines + kLineThreads - 1) / kLineThreads), unsigned(g.count));
    for (int p = 0; p < kInterpolationPasses; ++p) {
      interpolationPassKernel<<<lines, kLineThreads, 0, stream>>>(
          InterpolationPass(p), jobs, list + g.first, refs, area, output, scratch_, status);
      AFAM_CUDA_CHECK(cudaGetLastError());
    }
    const unsigned spread =
        unsigned(std::min<uint64_t>(kFinishBlocks, (g.points + kLineThreads - 1) / kLineThreads));
    interpolationFinishKernel<<<dim3(spread, unsigned(g.count)), kLineThreads, 0, stream>>>(
        jobs, list + g.first, output, scratch_, status);
    AFAM_CUDA_CHECK(cudaGetLastError());
  }
}

void GpuInterpolants::release() noexcept {
  if (tables_) (void)cudaFree(tables_);
  if (scratch_) (void)cudaFree(scratch_);
  if (staging_) (void)cudaFreeHost(staging_);
  tables_ = nullptr;
  scratch_ = nullptr;
  staging_ = nullptr;
  tablesCapacity_ = scratchCapacity_ = stagingCapacity_ = 0;
  (void)cudaGetLastError();
}

}  // namespace afam
