// SPDX-License-Identifier: BSD-3-Clause
// CUDA ray caster: one thread per pixel calling the shared afam::castRay / castRayWith
// (Core/include/afam/raycast.hpp). Nothing of the ray's math is written here.
#include "afam/cuda/gpu_renderer.hpp"

#include <cuda_runtime.h>

#include <algorithm>
#include <cstring>
#include <vector>

#include "cuda_check.hpp"

namespace afam {

namespace {

constexpr int kTileX = 16;
constexpr int kTileY = 8;

/// raycast.hpp's ModelSampler with the spline degree fixed at compile time. When every spline slot
/// of a frame has degree P on all axes, copying the slot's knots with `degree = P` lets the
/// compiler unroll the basis and tensor loops of evaluateModel and keep their small arrays in
/// registers; the values computed are those of ModelSampler (same functions, same operations).
template <int P>
struct FixedDegreeSampler {
  template <bool WithGradient>
  __device__ __forceinline__ bool sample(const FrameView& f, const float* p, float& value,
                                         float* gradient) const {
    float x[3];
    toVoxel(f, p, x);
    const int32_t slot = lookupSlot(f, x);
    if (slot < 0) return false;
    const FrameSlot& stored = f.slots[slot];
    float gv[3] = {0.f, 0.f, 0.f};
    if (stored.kind == kSlotRaw) {
      value = sampleRawSlot<WithGradient>(stored, f.pool, x, gv);
    } else {
      FrameSlot s = stored;
      s.knots[0].degree = P;
      s.knots[1].degree = P;
      s.knots[2].degree = P;
      value = sampleSplineSlot<WithGradient>(s, f.pool, x, gv);
    }
    if (WithGradient) {
      gradient[0] = gv[0] * f.voxelPerUnit[0];
      gradient[1] = gv[1] * f.voxelPerUnit[1];
      gradient[2] = gv[2] * f.voxelPerUnit[2];
    }
    return true;
  }
};

template <int P>
struct SamplerFor {
  using type = FixedDegreeSampler<P>;
};
template <>
struct SamplerFor<-1> {
  using type = ModelSampler;
};

/// Wraps a sampler and counts the samples it evaluated (untimed launches only).
template <typename Inner>
struct CountingSampler {
  Inner inner;
  unsigned* count;
  template <bool WithGradient>
  __device__ __forceinline__ bool sample(const FrameView& f, const float* p, float& value,
                                         float* gradient) const {
    const bool ok = inner.template sample<WithGradient>(f, p, value, gradient);
    if (ok) ++*count;
    return ok;
  }
};

template <bool Shaded, int P>
__global__ void __launch_bounds__(kTileX * kTileY)
    fullKernel(const FrameView f, float4* __restrict__ image) {
  const int px = int(blockIdx.x) * kTileX + int(threadIdx.x);
  const int py = int(blockIdx.y) * kTileY + int(threadIdx.y);
  if (px >= f.camera.width || py >= f.camera.height) return;
  const RGBA c = castRayWith<Shaded>(f, typename SamplerFor<P>::type{}, px, py);
  image[int64_t(py) * f.camera.width + px] = make_float4(c.r, c.g, c.b, c.a);
}

template <bool Shaded, int P>
__global__ void __launch_bounds__(kTileX * kTileY)
    countingKernel(const FrameView f, unsigned long long* total) {
  const int px = int(blockIdx.x) * kTileX + int(threadIdx.x);
  const int py = int(blockIdx.y) * kTileY + int(threadIdx.y);
  if (px >= f.camera.width || py >= f.camera.height) return;
  unsigned count = 0;
  CountingSampler<typename SamplerFor<P>::type> sampler{{}, &count};
  (void)castRayWith<Shaded>(f, sampler, px, py);
  atomicAdd(total, (unsigned long long)count);
}

/// Baseline: the same rays and sample positions as castRayWith, but every sample in the box is
/// only looked up and evaluated (value + gradient); no TF, shading, compositing or early exit.
template <int P>
__global__ void __launch_bounds__(kTileX * kTileY)
    bareKernel(const FrameView f, float* __restrict__ sink, unsigned long long* total) {
  const int px = int(blockIdx.x) * kTileX + int(threadIdx.x);
  const int py = int(blockIdx.y) * kTileY + int(threadIdx.y);
  if (px >= f.camera.width || py >= f.camera.height) return;
  const typename SamplerFor<P>::type sampler{};
  float d[3];
  rayDirection(f.camera, px, py, d);
  float tEnter, tExit, sum = 0.f;
  unsigned count = 0;
  if (intersectBox(f.camera.eye, d, f.boxLo, f.boxHi, tEnter, tExit)) {
    const float tStart = rc::maxf(tEnter, f.camera.nearDistance);
    const float dt = f.sampleDistance;
    if (tExit >= tStart && dt > 0.f) {
      int64_t k = int64_t(ceilf(tStart / dt));
      const int64_t kEnd = int64_t(floorf(tExit / dt));
      for (; k <= kEnd; ++k) {
        const float t = float(k) * dt;
        const float p[3] = {f.camera.eye[0] + t * d[0], f.camera.eye[1] + t * d[1],
                            f.camera.eye[2] + t * d[2]};
        float value = 0.f, g[3] = {0.f, 0.f, 0.f};
        if (!sampler.template sample<true>(f, p, value, g)) continue;
        sum += value + g[0] + g[1] + g[2];
        ++count;
      }
    }
  }
  sink[int64_t(py) * f.camera.width + px] = sum;
  if (total) atomicAdd(total, (unsigned long long)count);
}

template <typename Kernel>
std::string describe(Kernel kernel, const char* name) {
  cudaFuncAttributes a{};
  if (cudaFuncGetAttributes(&a, kernel) != cudaSuccess) {
    (void)cudaGetLastError();
    return name;
  }
  return std::string(name) + ": " + std::to_string(a.numRegs) + " registers, " +
         std::to_string(a.localSizeBytes) + " bytes local";
}

/// Degree shared by all spline slots on all axes, or -1 (mixed, or degree outside 1..5).
int uniformDegree(const FrameView& v) {
  int degree = 0;
  for (int32_t s = 0; s < v.slotCount; ++s) {
    const FrameSlot& slot = v.slots[s];
    if (slot.kind == kSlotRaw) continue;
    for (int a = 0; a < 3; ++a) {
      const int d = slot.knots[a].degree;
      if (degree == 0) degree = d;
      if (d != degree) return -1;
    }
  }
  return degree >= 1 && degree <= kMaxDegree ? degree : -1;
}

size_t align256(size_t n) { return (n + 255) & ~size_t(255); }

}  // namespace

double GpuKernelTiming::median() const {
  if (ms.empty()) return 0;
  std::vector<double> v = ms;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

uint64_t GpuRenderer::slotFloats(const FrameSlot& slot) {
  return uint64_t(slot.knots[0].ncp) * uint64_t(slot.knots[1].ncp) * uint64_t(slot.knots[2].ncp);
}

uint64_t GpuRenderer::defaultSlotKey(const FrameSlot& slot) {
  auto mix = [](uint64_t h, uint64_t v) {
    h ^= v + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    h ^= h >> 31;
    h *= 0xbf58476d1ce4e5b9ull;
    return h ^ (h >> 29);
  };
  uint64_t h = 0x243f6a8885a308d3ull;
  h = mix(h, uint64_t(uint32_t(slot.kind)) | (uint64_t(uint32_t(slot.level)) << 32));
  for (int a = 0; a < 3; ++a) {
    uint32_t lo = 0, inv = 0;
    std::memcpy(&lo, &slot.lo[a], 4);
    std::memcpy(&inv, &slot.invExtent[a], 4);
    h = mix(h, (uint64_t(lo) << 32) | inv);
    h = mix(h, (uint64_t(uint32_t(slot.knots[a].ncp)) << 32) | uint32_t(slot.knots[a].degree));
  }
  return h;
}

struct GpuRenderer::Impl {
  GpuModelPool pool;
  cudaStream_t stream = nullptr;
  // Frame tables: one pinned host buffer, one device buffer.
  unsigned char* hostTables = nullptr;
  unsigned char* deviceTables = nullptr;
  size_t tablesCapacity = 0;
  // Image.
  float4* deviceImage = nullptr;
  float4* hostImage = nullptr;
  size_t imageCapacity = 0;  // pixels
  unsigned long long* deviceCounter = nullptr;
  cudaEvent_t events[4] = {nullptr, nullptr, nullptr, nullptr};

  Impl(size_t budget, int device) : pool(budget, device) {
    stream = static_cast<cudaStream_t>(pool.stream());
    try {
      for (cudaEvent_t& e : events) AFAM_CUDA_CHECK(cudaEventCreate(&e));
      AFAM_CUDA_CHECK(cudaMalloc(reinterpret_cast<void**>(&deviceCounter), 8));
    } catch (...) {
      release();
      throw;
    }
  }
  ~Impl() { release(); }

  void release() noexcept {
    if (stream) (void)cudaStreamSynchronize(stream);
    for (cudaEvent_t& e : events)
      if (e) (void)cudaEventDestroy(e), e = nullptr;
    if (hostTables) (void)cudaFreeHost(hostTables);
    if (deviceTables) (void)cudaFree(deviceTables);
    if (deviceImage) (void)cudaFree(deviceImage);
    if (hostImage) (void)cudaFreeHost(hostImage);
    if (deviceCounter) (void)cudaFree(deviceCounter);
    hostTables = deviceTables = nullptr;
    deviceImage = hostImage = nullptr;
    deviceCounter = nullptr;
    (void)cudaGetLastError();
  }

  void reserveTables(size_t bytes) {
    if (bytes <= tablesCapacity) return;
    AFAM_CUDA_CHECK(cudaStreamSynchronize(stream));
    size_t grown = std::max<size_t>(bytes, 2 * tablesCapacity);
    if (hostTables) AFAM_CUDA_CHECK(cudaFreeHost(hostTables));
    if (deviceTables) AFAM_CUDA_CHECK(cudaFree(deviceTables));
    hostTables = deviceTables = nullptr;
    tablesCapacity = 0;
    AFAM_CUDA_CHECK(cudaMallocHost(reinterpret_cast<void**>(&hostTables), grown));
    AFAM_CUDA_CHECK(cudaMalloc(reinterpret_cast<void**>(&deviceTables), grown));
    tablesCapacity = grown;
  }

  void reserveImage(size_t pixels) {
    if (pixels <= imageCapacity) return;
    AFAM_CUDA_CHECK(cudaStreamSynchronize(stream));
    if (deviceImage) AFAM_CUDA_CHECK(cudaFree(deviceImage));
    if (hostImage) AFAM_CUDA_CHECK(cudaFreeHost(hostImage));
    deviceImage = hostImage = nullptr;
    imageCapacity = 0;
    AFAM_CUDA_CHECK(cudaMalloc(reinterpret_cast<void**>(&deviceImage), pixels * sizeof(float4)));
    AFAM_CUDA_CHECK(cudaMallocHost(reinterpret_cast<void**>(&hostImage), pixels * sizeof(float4)));
    imageCapacity = pixels;
  }

  /// Makes every slot's model resident, uploads the frame tables and returns the device view.
  /// All copies are queued on `stream`; kernels queued after it see the data.
  FrameView upload(const FrameView& v, const uint64_t* keys, uint64_t* modelsUploaded,
                   uint64_t* bytesUploaded) {
    if (v.camera.width < 1 || v.camera.height < 1)
      throw InvalidArgument("GpuRenderer: image size " + std::to_string(v.camera.width) + " x " +
                            std::to_string(v.camera.height) + " is empty");
    if (v.slotCount > 0 && (!v.slots || !v.pool))
      throw InvalidArgument("GpuRenderer: frame has slots but no slot table or pool");
    const PoolStats before = pool.stats();
    pool.beginFrame();
    // Layout of the tables buffer.
    size_t boundsOffset[3], size = 0;
    for (int a = 0; a < 3; ++a) {
      boundsOffset[a] = size;
      size = align256(size + sizeof(float) * size_t(v.gridDims[a] + 1));
    }
    const size_t cells = size_t(v.gridDims[0]) * size_t(v.gridDims[1]) * size_t(v.gridDims[2]);
    const size_t cellOffset = size;
    size = align256(size + sizeof(int32_t) * cells);
    const size_t slotOffset = size;
    size = align256(size + sizeof(FrameSlot) * size_t(std::max(v.slotCount, 0)));
    const size_t tfOffset = size;
    size = align256(size + sizeof(float) * 4 * size_t(std::max(v.tfSize, 0)));
    reserveTables(size);
    // Wait until the previous frame's table copy has left the pinned buffer.
    AFAM_CUDA_CHECK(cudaStreamSynchronize(stream));
    for (int a = 0; a < 3; ++a)
      if (v.cellBounds[a])
        std::memcpy(hostTables + boundsOffset[a], v.cellBounds[a],
                    sizeof(float) * size_t(v.gridDims[a] + 1));
    if (v.cellSlot) std::memcpy(hostTables + cellOffset, v.cellSlot, sizeof(int32_t) * cells);
    if (v.tf && v.tfSize > 0)
      std::memcpy(hostTables + tfOffset, v.tf, sizeof(float) * 4 * size_t(v.tfSize));
    auto* slots = reinterpret_cast<FrameSlot*>(hostTables + slotOffset);
    for (int32_t s = 0; s < v.slotCount; ++s) {
      FrameSlot slot = v.slots[s];
      const uint64_t floats = slotFloats(slot);
      const uint64_t key = keys ? keys[s] : defaultSlotKey(slot);
      const size_t byteOffset =
          pool.acquire(key, v.pool + slot.offset, size_t(floats) * sizeof(float));
      slot.offset = byteOffset / sizeof(float);
      slots[s] = slot;
    }
    pool.flush();
    AFAM_CUDA_CHECK(
        cudaMemcpyAsync(deviceTables, hostTables, size, cudaMemcpyHostToDevice, stream));
    const PoolStats after = pool.stats();
    if (modelsUploaded) *modelsUploaded = after.uploads - before.uploads;
    if (bytesUploaded) *bytesUploaded = after.bytesUploaded - before.bytesUploaded;

    FrameView d = v;
    for (int a = 0; a < 3; ++a)
      d.cellBounds[a] = reinterpret_cast<const float*>(deviceTables + boundsOffset[a]);
    d.cellSlot = reinterpret_cast<const int32_t*>(deviceTables + cellOffset);
    d.slots = reinterpret_cast<const FrameSlot*>(deviceTables + slotOffset);
    d.tf = reinterpret_cast<const float*>(deviceTables + tfOffset);
    d.pool = static_cast<const float*>(pool.arena());
    return d;
  }
};

namespace {

struct LaunchConfig {
  dim3 grid, block;
};
LaunchConfig config(const FrameView& v) {
  return {dim3(unsigned((v.camera.width + kTileX - 1) / kTileX),
               unsigned((v.camera.height + kTileY - 1) / kTileY)),
          dim3(kTileX, kTileY)};
}

template <bool Shaded, int P>
std::string launchFullT(const FrameView& d, float4* image, cudaStream_t stream, bool describeIt) {
  const LaunchConfig c = config(d);
  fullKernel<Shaded, P><<<c.grid, c.block, 0, stream>>>(d, image);
  AFAM_CUDA_CHECK(cudaGetLastError());
  if (!describeIt) return {};
  const std::string name = std::string("full<") + (Shaded ? "shaded" : "unshaded") +
                           ",p=" + (P < 0 ? std::string("any") : std::to_string(P)) + ">";
  return describe(fullKernel<Shaded, P>, name.c_str());
}

template <bool Shaded, int P>
void launchCountT(const FrameView& d, unsigned long long* total, cudaStream_t stream) {
  const LaunchConfig c = config(d);
  countingKernel<Shaded, P><<<c.grid, c.block, 0, stream>>>(d, total);
  AFAM_CUDA_CHECK(cudaGetLastError());
}

template <int P>
std::string launchBareT(const FrameView& d, float* sink, unsigned long long* total,
                        cudaStream_t stream, bool describeIt) {
  const LaunchConfig c = config(d);
  bareKernel<P><<<c.grid, c.block, 0, stream>>>(d, sink, total);
  AFAM_CUDA_CHECK(cudaGetLastError());
  if (!describeIt) return {};
  const std::string name = "bare<p=" + (P < 0 ? std::string("any") : std::to_string(P)) + ">";
  return describe(bareKernel<P>, name.c_str());
}

std::string launchFull(bool shaded, int p, const FrameView& d, float4* image, cudaStream_t s,
                       bool describeIt) {
  if (shaded) {
    switch (p) {
      case 1: return launchFullT<true, 1>(d, image, s, describeIt);
      case 2: return launchFullT<true, 2>(d, image, s, describeIt);
      case 3: return launchFullT<true, 3>(d, image, s, describeIt);
      case 4: return launchFullT<true, 4>(d, image, s, describeIt);
      case 5: return launchFullT<true, 5>(d, image, s, describeIt);
      default: return launchFullT<true, -1>(d, image, s, describeIt);
    }
  }
  switch (p) {
    case 1: return launchFullT<false, 1>(d, image, s, describeIt);
    case 2: return launchFullT<false, 2>(d, image, s, describeIt);
    case 3: return launchFullT<false, 3>(d, image, s, describeIt);
    case 4: return launchFullT<false, 4>(d, image, s, describeIt);
    case 5: return launchFullT<false, 5>(d, image, s, describeIt);
    default: return launchFullT<false, -1>(d, image, s, describeIt);
  }
}

void launchCount(bool shaded, int p, const FrameView& d, unsigned long long* total,
                 cudaStream_t s) {
  // Counting is for benchmarks: the common degree 2 and the generic path are enough.
  if (shaded) {
    if (p == 2) return launchCountT<true, 2>(d, total, s);
    return launchCountT<true, -1>(d, total, s);
  }
  if (p == 2) return launchCountT<false, 2>(d, total, s);
  return launchCountT<false, -1>(d, total, s);
}

std::string launchBare(int p, const FrameView& d, float* sink, unsigned long long* total,
                       cudaStream_t s, bool describeIt) {
  if (p == 2) return launchBareT<2>(d, sink, total, s, describeIt);
  return launchBareT<-1>(d, sink, total, s, describeIt);
}

float elapsed(cudaEvent_t a, cudaEvent_t b) {
  float ms = 0.f;
  AFAM_CUDA_CHECK(cudaEventElapsedTime(&ms, a, b));
  return ms;
}

}  // namespace

GpuRenderer::GpuRenderer(size_t poolBudgetBytes, int device)
    : impl_(std::make_unique<Impl>(poolBudgetBytes, device)) {}

GpuRenderer::~GpuRenderer() = default;

GpuModelPool& GpuRenderer::pool() { return impl_->pool; }
const GpuModelPool& GpuRenderer::pool() const { return impl_->pool; }

void GpuRenderer::render(const FrameView& view, const uint64_t* slotKeys, float* rgba,
                         GpuFrameTimes* times) {
  Impl& m = *impl_;
  const size_t pixels = size_t(view.camera.width) * size_t(view.camera.height);
  if (pixels > 0) m.reserveImage(pixels);
  AFAM_CUDA_CHECK(cudaEventRecord(m.events[0], m.stream));
  GpuFrameTimes t;
  const FrameView d = m.upload(view, slotKeys, &t.modelsUploaded, &t.bytesUploaded);
  AFAM_CUDA_CHECK(cudaEventRecord(m.events[1], m.stream));
  if (poison_)
    AFAM_CUDA_CHECK(cudaMemsetAsync(m.deviceImage, 0xFF, pixels * sizeof(float4), m.stream));
  const int p = specialise_ ? uniformDegree(view) : -1;
  kernelInfo_ = launchFull(view.shading != 0, p, d, m.deviceImage, m.stream, true);
  AFAM_CUDA_CHECK(cudaEventRecord(m.events[2], m.stream));
  AFAM_CUDA_CHECK(cudaMemcpyAsync(m.hostImage, m.deviceImage, pixels * sizeof(float4),
                                  cudaMemcpyDeviceToHost, m.stream));
  AFAM_CUDA_CHECK(cudaEventRecord(m.events[3], m.stream));
  AFAM_CUDA_CHECK(cudaEventSynchronize(m.events[3]));
  std::memcpy(rgba, m.hostImage, pixels * sizeof(float4));
  if (times) {
    t.uploadMs = elapsed(m.events[0], m.events[1]);
    t.kernelMs = elapsed(m.events[1], m.events[2]);
    t.downloadMs = elapsed(m.events[2], m.events[3]);
    t.totalMs = elapsed(m.events[0], m.events[3]);
    *times = t;
  }
}

GpuKernelTiming GpuRenderer::timeKernel(const FrameView& view, const uint64_t* slotKeys,
                                        GpuKernelKind kind, int repetitions) {
  Impl& m = *impl_;
  const size_t pixels = size_t(view.camera.width) * size_t(view.camera.height);
  m.reserveImage(pixels);
  const FrameView d = m.upload(view, slotKeys, nullptr, nullptr);
  const int p = specialise_ ? uniformDegree(view) : -1;
  const bool shaded = view.shading != 0;
  auto* sink = reinterpret_cast<float*>(m.deviceImage);
  GpuKernelTiming timing;
  // Untimed launch that counts the evaluated samples.
  AFAM_CUDA_CHECK(cudaMemsetAsync(m.deviceCounter, 0, 8, m.stream));
  if (kind == GpuKernelKind::Full)
    launchCount(shaded, p, d, m.deviceCounter, m.stream);
  else
    (void)launchBare(p, d, sink, m.deviceCounter, m.stream, false);
  unsigned long long count = 0;
  AFAM_CUDA_CHECK(cudaMemcpyAsync(&count, m.deviceCounter, 8, cudaMemcpyDeviceToHost, m.stream));
  AFAM_CUDA_CHECK(cudaStreamSynchronize(m.stream));
  timing.samples = count;
  for (int r = -1; r < repetitions; ++r) {  // r = -1: warm-up
    AFAM_CUDA_CHECK(cudaEventRecord(m.events[0], m.stream));
    const std::string info = kind == GpuKernelKind::Full
                                 ? launchFull(shaded, p, d, m.deviceImage, m.stream, r == -1)
                                 : launchBare(p, d, sink, nullptr, m.stream, r == -1);
    if (r == -1) kernelInfo_ = info;
    AFAM_CUDA_CHECK(cudaEventRecord(m.events[1], m.stream));
    AFAM_CUDA_CHECK(cudaEventSynchronize(m.events[1]));
    if (r >= 0) timing.ms.push_back(elapsed(m.events[0], m.events[1]));
  }
  return timing;
}

}  // namespace afam
