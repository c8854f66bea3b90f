// SPDX-License-Identifier: BSD-3-Clause
// Batched least-squares residuals on the GPU (least_squares_batch.hpp): one thread block of
// kLsqLanes threads a request. The block's mean and squares, then plane by plane along z the
// centred samples, their x contraction and their y contraction (in shared memory, the rows of
// Qx^T and Qy^T beside them), the slices after y in global scratch, and the z contraction's energy
// column by column (a thread's column copied to shared memory once, the rows of Qz^T beside); every
// sum in the order of least_squares_order.hpp (compiled with -fmad=false), so the doubles are the
// CPU reference's.
#include <cuda_runtime.h>

#include <algorithm>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/cuda/common/gpu_error.hpp"
#include "afam/cuda/encode/make_gpu_least_squares.hpp"
#include "afam/ranks/device_selection.hpp"
#include "afam/sampling/level_filter.hpp"
#include "afam/search/least_squares_order.hpp"
#include "common/cuda_check.hpp"
#include "common/growing_array.hpp"
#include "encode/gpu_volume_copy.hpp"

namespace afam {

namespace {

using cuda_detail::GrowingArray;

/// One request on the device: offsets into the batch's buffers.
struct LsqJob {
  uint64_t samples = 0;       ///< floats, of the block's first sample
  uint64_t scratch = 0;       ///< doubles, of its slices after y
  uint64_t q[3] = {0, 0, 0};  ///< doubles, of the rows of Q^T per axis
  int n[3] = {0, 0, 0}, k[3] = {0, 0, 0};
};

/// Shared doubles a request needs: along x and y, the plane (rows padded by one), after x, and
/// the rows of Qx and Qy (y's padded by one); along z, a column a thread and the rows of Qz.
uint64_t sharedDoubles(Int3 n, Int3 k) {
  const uint64_t alongXY = uint64_t(n[1]) * (n[0] + 1) + uint64_t(k[0]) * n[1] +
                           uint64_t(k[0]) * n[0] + uint64_t(k[1]) * (n[1] + 1);
  const uint64_t alongZ = uint64_t(n[2]) * kLsqLanes + uint64_t(k[2]) * n[2];
  return std::max(alongXY, alongZ);
}

/// Outputs a thread sums at once (independent chains in flight; each in the reference's order).
constexpr int kOutputs = 4;

__device__ double treeSumShared(double* lanes, double mine) {
  lanes[threadIdx.x] = mine;
  __syncthreads();
  for (int s = kLsqLanes / 2; s > 0; s >>= 1) {
    if (int(threadIdx.x) < s) lanes[threadIdx.x] += lanes[threadIdx.x + s];
    __syncthreads();
  }
  const double sum = lanes[0];
  __syncthreads();
  return sum;
}

__device__ void copyRows(const double* from, int rows, int cols, double* to, int stride) {
  for (int e = threadIdx.x; e < rows * cols; e += kLsqLanes)
    to[(e / cols) * stride + e % cols] = from[e];
}

__global__ void __launch_bounds__(kLsqLanes)
    residualKernel(const LsqJob* jobs, const float* samples, const double* q, double* scratch,
                   double2* out) {
  extern __shared__ double shared[];
  __shared__ double lanes[kLsqLanes];
  const LsqJob job = jobs[blockIdx.x];
  const Int3 n{job.n[0], job.n[1], job.n[2]}, k{job.k[0], job.k[1], job.k[2]};
  const LsqShape shape = lsqShape(n, k);
  const float* s = samples + job.samples;
  double* afterY = scratch + job.scratch;
  const int planeStride = n[0] + 1, qyStride = n[1] + 1;
  double* plane = shared;
  double* afterX = plane + int64_t(n[1]) * planeStride;
  double* qx = afterX + shape.afterX;
  double* qy = qx + int64_t(k[0]) * n[0];
  copyRows(q + job.q[0], k[0], n[0], qx, n[0]);
  copyRows(q + job.q[1], k[1], n[1], qy, qyStride);
  double part = 0;
  for (int z = 0; z < n[2]; ++z)
    for (int64_t e = threadIdx.x; e < shape.plane; e += kLsqLanes)
      part += double(s[z * shape.plane + e]);
  const double mean = treeSumShared(lanes, part) / double(shape.plane * n[2]);
  part = 0;
  for (int z = 0; z < n[2]; ++z) {
    for (int64_t e = threadIdx.x; e < shape.plane; e += kLsqLanes) {
      const double d = double(s[z * shape.plane + e]) - mean;
      plane[(e / n[0]) * planeStride + e % n[0]] = d;
      part += d * d;
    }
    __syncthreads();
    double v[kOutputs];
    for (int64_t o = threadIdx.x; o < shape.afterX; o += kOutputs * kLsqLanes) {
      lsqAlongX<kOutputs>(qx, plane, planeStride, n, o, kLsqLanes, shape.afterX, v);
      for (int r = 0; r < kOutputs && o + r * kLsqLanes < shape.afterX; ++r)
        afterX[o + r * kLsqLanes] = v[r];
    }
    __syncthreads();
    for (int64_t o = threadIdx.x; o < shape.slice; o += kOutputs * kLsqLanes) {
      lsqAlongY<kOutputs>(qy, qyStride, afterX, n, k, o, kLsqLanes, shape.slice, v);
      for (int r = 0; r < kOutputs && o + r * kLsqLanes < shape.slice; ++r)
        afterY[z * shape.slice + o + r * kLsqLanes] = v[r];
    }
    __syncthreads();
  }
  const double squares = treeSumShared(lanes, part);  // its barrier ends the x and y passes
  // Along z: each thread's column of the slices after y into shared memory, Qz's rows beside.
  double* column = shared;
  double* qz = column + int64_t(n[2]) * kLsqLanes;
  copyRows(q + job.q[2], k[2], n[2], qz, n[2]);
  __syncthreads();
  part = 0;
  for (int64_t j = threadIdx.x; j < shape.slice; j += kLsqLanes) {
    for (int z = 0; z < n[2]; ++z)
      column[z * kLsqLanes + threadIdx.x] = afterY[z * shape.slice + j];
    part += lsqColumnEnergy<kOutputs>(qz, column + threadIdx.x, kLsqLanes, n, k);
  }
  const double energy = treeSumShared(lanes, part);
  if (threadIdx.x == 0) out[blockIdx.x] = make_double2(squares, squares - energy);
}

/// A box of the volume's copy gathered into the batch's samples (setBlocksIn).
struct GatherBox {
  Index3 origin{};
  Int3 n{};
  uint64_t out = 0;  ///< floats, of its first sample in the batch's samples
};

/// Each box's samples from the volume (boxSample: the floats the CPU's sampling makes), a grid
/// row a box, its threads striding over the box.
template <typename T>
__global__ void __launch_bounds__(kLsqLanes)
    gatherBoxesKernel(const T* volume, int64_t rowSize, int64_t planeSize, const GatherBox* boxes,
                      float* out) {
  const GatherBox b = boxes[blockIdx.y];
  const int64_t count = int64_t(b.n[0]) * b.n[1] * b.n[2];
  for (int64_t s = int64_t(blockIdx.x) * kLsqLanes + threadIdx.x; s < count;
       s += int64_t(gridDim.x) * kLsqLanes)
    out[b.out + uint64_t(s)] = boxSample(volume, rowSize, planeSize, b.origin, b.n, s);
}

class GpuLeastSquaresBatch final : public LeastSquaresBatch {
 public:
  explicit GpuLeastSquaresBatch(int device) : device_(device) {
    AFAM_CUDA_CHECK(cudaSetDevice(device));
    cudaDeviceProp prop{};
    AFAM_CUDA_CHECK(cudaGetDeviceProperties(&prop, device));
    name_ = prop.name;
    multiprocessors_ = prop.multiProcessorCount;
    sharedLimit_ = uint64_t(prop.sharedMemPerBlockOptin) - kLsqLanes * sizeof(double) - 1024;
    AFAM_CUDA_CHECK(cudaFuncSetAttribute(
        residualKernel, cudaFuncAttributeMaxDynamicSharedMemorySize, int(sharedLimit_)));
    AFAM_CUDA_CHECK(cudaStreamCreateWithFlags(&stream_, cudaStreamNonBlocking));
  }
  ~GpuLeastSquaresBatch() override { (void)cudaStreamDestroy(stream_); }

  void setBlocks(const std::vector<const float*>& samples, const std::vector<Int3>& n,
                 int degree) override {
    AFAM_CUDA_CHECK(cudaSetDevice(device_));
    degree_ = degree;
    n_ = n;
    cpu_.setBlocks(samples, n, degree);
    offsets_.assign(samples.size() + 1, 0);
    for (size_t b = 0; b < samples.size(); ++b)
      offsets_[b + 1] = offsets_[b] + uint64_t(n[b][0]) * n[b][1] * n[b][2];
    // One copy through pinned memory: pageable copies are staged by the driver a block at a time.
    const size_t bytes = offsets_.back() * sizeof(float);
    AFAM_CUDA_CHECK(cudaStreamSynchronize(stream_));  // the staging buffer's last copy is done
    staging_.reserve(bytes);
    samples_.reserve(bytes);
    stage(samples);
    AFAM_CUDA_CHECK(
        cudaMemcpyAsync(samples_.data, staging_.data, bytes, cudaMemcpyHostToDevice, stream_));
  }

  void setBlocksIn(const VolumeBoxes& boxes, const std::vector<const float*>& samples,
                   const std::vector<Int3>& n, int degree) override;
  void residuals(const std::vector<LsqRequest>& requests, std::vector<LsqResidual>& out) override;
  std::string description() const override { return name_; }
  /// A request a multiprocessor: a fine level's requests take most of one's shared memory.
  int64_t requestsAtOnce() const override { return multiprocessors_; }

 private:
  /// Jobs of the requests the GPU takes (their index in `requests` in `taken`), the others'
  /// indices in `onCpu`; the matrices they need uploaded; returns the shared bytes of the largest.
  uint64_t prepare(const std::vector<LsqRequest>& requests, std::vector<LsqJob>& jobs,
                   std::vector<size_t>& taken, std::vector<size_t>& onCpu);

  /// Copies the blocks' samples into the staging buffer, on a few threads: one thread's copy of a
  /// batch (about 100 MB) held the batch's asking for longer than its residuals.
  void stage(const std::vector<const float*>& samples) {
    const size_t threads = std::min<size_t>(
        samples.size(),
        std::clamp<size_t>(std::thread::hardware_concurrency(), 1, kStagingThreads));
    auto copy = [&](size_t part) {
      for (size_t b = samples.size() * part / threads; b < samples.size() * (part + 1) / threads;
           ++b)
        std::copy(samples[b], samples[b] + (offsets_[b + 1] - offsets_[b]),
                  staging_.as<float>() + offsets_[b]);
    };
    std::vector<std::thread> others;
    for (size_t part = 1; part < threads; ++part) try {
        others.emplace_back(copy, part);
      } catch (const std::system_error&) {  // no thread to be had: this one copies the part
        copy(part);
      }
    if (threads > 0) copy(0);
    for (std::thread& t : others) t.join();
  }

  static constexpr size_t kStagingThreads = 8;
  int device_ = 0, degree_ = 2, multiprocessors_ = 1;
  std::string name_;
  uint64_t sharedLimit_ = 0;
  cudaStream_t stream_ = nullptr;
  CpuLeastSquaresBatch cpu_;
  std::vector<Int3> n_;
  std::vector<uint64_t> offsets_;
  std::vector<GatherBox> boxes_;  ///< setBlocksIn's, until their copy to the device is done
  AxisProjections projections_;
  size_t uploadedProjections_ = 0;
  GrowingArray samples_, matrices_, scratch_, jobs_, results_, gather_, staging_{true};
};

void GpuLeastSquaresBatch::setBlocksIn(const VolumeBoxes& boxes,
                                       const std::vector<const float*>& samples,
                                       const std::vector<Int3>& n, int degree) {
  const GpuVolumeCopy v = gpuVolumeCopy(boxes.copy);
  if (!v.data || v.device != device_ || boxes.origins.size() != n.size() || n.size() > 65535)
    return setBlocks(samples, n, degree);  // (a grid row a box: at most 65,535 of them)
  for (size_t b = 0; b < n.size(); ++b)
    for (int a = 0; a < 3; ++a)
      if (boxes.origins[b][a] < 0 || n[b][a] < 0 || boxes.origins[b][a] + n[b][a] > v.dims[a])
        throw InvalidArgument("GpuLeastSquaresBatch: box " + std::to_string(b) + " of " +
                              std::to_string(n[b][a]) + " samples from " +
                              std::to_string(boxes.origins[b][a]) + " outside the copy's " +
                              std::to_string(v.dims[a]) + " along axis " + std::to_string(a));
  AFAM_CUDA_CHECK(cudaSetDevice(device_));
  degree_ = degree;
  n_ = n;
  cpu_.setBlocks(samples, n, degree);  // for the requests too large for a multiprocessor
  offsets_.assign(n.size() + 1, 0);
  AFAM_CUDA_CHECK(cudaStreamSynchronize(stream_));  // boxes_' last copy is done
  boxes_.resize(n.size());
  int64_t largest = 0;
  for (size_t b = 0; b < n.size(); ++b) {
    const int64_t count = int64_t(n[b][0]) * n[b][1] * n[b][2];
    boxes_[b] = {boxes.origins[b], n[b], offsets_[b]};
    offsets_[b + 1] = offsets_[b] + uint64_t(count);
    largest = std::max(largest, count);
  }
  if (n.empty()) return;
  samples_.reserve(offsets_.back() * sizeof(float));
  gather_.reserve(boxes_.size() * sizeof(GatherBox));
  AFAM_CUDA_CHECK(cudaMemcpyAsync(gather_.data, boxes_.data(), boxes_.size() * sizeof(GatherBox),
                                  cudaMemcpyHostToDevice, stream_));
  const dim3 grid(unsigned(std::clamp<int64_t>((largest + kLsqLanes - 1) / kLsqLanes, 1, 64)),
                  unsigned(n.size()));
  const int64_t X = v.dims[0], XY = v.dims[0] * v.dims[1];
  withCopyType(v.type, [&](auto* typed) {
    gatherBoxesKernel<<<grid, kLsqLanes, 0, stream_>>>(
        static_cast<decltype(typed)>(v.data), X, XY, gather_.as<GatherBox>(), samples_.as<float>());
  });
  AFAM_CUDA_CHECK(cudaGetLastError());
}

uint64_t GpuLeastSquaresBatch::prepare(const std::vector<LsqRequest>& requests,
                                       std::vector<LsqJob>& jobs, std::vector<size_t>& taken,
                                       std::vector<size_t>& onCpu) {
  uint64_t largest = 0, scratch = 0;
  for (size_t r = 0; r < requests.size(); ++r) {
    const Int3 n = n_.at(size_t(requests[r].block)), k = requests[r].ncp;
    const uint64_t bytes = sharedDoubles(n, k) * sizeof(double);
    if (bytes > sharedLimit_) {
      onCpu.push_back(r);
      continue;
    }
    LsqJob j;
    j.samples = offsets_[size_t(requests[r].block)];
    j.scratch = scratch;
    for (int a = 0; a < 3; ++a) {
      j.q[a] = projections_.offsetOf(n[a], k[a], degree_);
      j.n[a] = n[a];
      j.k[a] = k[a];
    }
    scratch += uint64_t(lsqShape(n, k).afterY);
    largest = std::max(largest, bytes);
    jobs.push_back(j);
    taken.push_back(r);
  }
  const std::vector<double>& q = projections_.values();
  if (q.size() > uploadedProjections_) {  // new matrices: upload them all again (a few MB)
    matrices_.reserve(q.size() * sizeof(double));
    AFAM_CUDA_CHECK(cudaMemcpyAsync(matrices_.data, q.data(), q.size() * sizeof(double),
                                    cudaMemcpyHostToDevice, stream_));
    uploadedProjections_ = q.size();
  }
  scratch_.reserve(scratch * sizeof(double));
  return largest;
}

void GpuLeastSquaresBatch::residuals(const std::vector<LsqRequest>& requests,
                                     std::vector<LsqResidual>& out) {
  AFAM_CUDA_CHECK(cudaSetDevice(device_));
  out.assign(requests.size(), LsqResidual{});
  std::vector<LsqJob> jobs;
  std::vector<size_t> taken, onCpu;
  const uint64_t shared = prepare(requests, jobs, taken, onCpu);
  std::vector<double2> results(jobs.size());
  if (!jobs.empty()) {
    jobs_.reserve(jobs.size() * sizeof(LsqJob));
    results_.reserve(jobs.size() * sizeof(double2));
    AFAM_CUDA_CHECK(cudaMemcpyAsync(jobs_.data, jobs.data(), jobs.size() * sizeof(LsqJob),
                                    cudaMemcpyHostToDevice, stream_));
    residualKernel<<<unsigned(jobs.size()), kLsqLanes, shared, stream_>>>(
        jobs_.as<LsqJob>(), samples_.as<float>(), matrices_.as<double>(), scratch_.as<double>(),
        results_.as<double2>());
    AFAM_CUDA_CHECK(cudaGetLastError());
    AFAM_CUDA_CHECK(cudaMemcpyAsync(results.data(), results_.data, jobs.size() * sizeof(double2),
                                    cudaMemcpyDeviceToHost, stream_));
  }
  std::vector<LsqRequest> cpuRequests;
  for (size_t r : onCpu) cpuRequests.push_back(requests[r]);
  std::vector<LsqResidual> cpuResults;
  cpu_.residuals(cpuRequests, cpuResults);  // while the GPU works
  AFAM_CUDA_CHECK(cudaStreamSynchronize(stream_));
  for (size_t i = 0; i < taken.size(); ++i) out[taken[i]] = {results[i].x, results[i].y};
  for (size_t i = 0; i < onCpu.size(); ++i) out[onCpu[i]] = cpuResults[i];
}

}  // namespace

std::shared_ptr<LeastSquaresBatch> makeGpuLeastSquares(
    const std::function<void(const std::string&)>& report, int device) {
  std::string why;
  if (!gpuAvailable(&why)) {
    report(why);
    return nullptr;
  }
  try {  // by default one GPU per MPI rank on a node with several (device_selection.hpp)
    return std::make_shared<GpuLeastSquaresBatch>(device >= 0 ? device
                                                              : selectGpuDevice(gpuDeviceCount()));
  } catch (const GpuError& e) {
    report(e.what());
    return nullptr;
  }
}

}  // namespace afam
