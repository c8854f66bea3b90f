// SPDX-License-Identifier: BSD-3-Clause
// Host side of the CUDA ray caster: model pool, frame tables, image, timing. The kernels are in
// kernels.cuh (one thread per pixel calling the shared afam::castRay), built once per
// floating-point contract (kernels_exact.cu, kernels_fma.cu, kernels_fast.cu).
#include "afam/cuda/render/gpu_renderer.hpp"

#include <cuda_runtime.h>

#include <algorithm>
#include <cstring>
#include <unordered_map>
#include <vector>

#include "afam/base/hash.hpp"
#include "common/cuda_check.hpp"
#include "render/kernel_launch.hpp"

namespace afam {

namespace {

/// Degree shared by all spline slots on all axes, or -1 (mixed, or degree outside 1..5).
int uniformDegree(const FrameView& v) {
  int degree = 0;
  for (int32_t s = 0; s < v.slotCount; ++s) {
    const FrameSlot& slot = v.slots[s];
    if (slot.kind != kSlotSpline) continue;
    for (int a = 0; a < 3; ++a) {
      const int d = slot.knots[a].degree;
      if (degree == 0) degree = d;
      if (d != degree) return -1;
    }
  }
  return degree >= 1 && degree <= kMaxDegree ? degree : -1;
}

size_t align256(size_t n) { return (n + 255) & ~size_t(255); }

/// Floats of slot s's model expanded to float32 points (its compact form set aside).
uint64_t expandedFloats(FrameSlot slot) {
  slot.codeWidth = 0;
  slot.codeTable = 0;
  return slotFloatCount(slot);
}

/// Whether some slot's model comes in its compact form (not as a stored payload to decode).
bool hasCompactModels(const FrameView& v, const GpuStoredSlot* stored) {
  for (int32_t s = 0; s < v.slotCount; ++s)
    if (v.slots[s].codeWidth > 0 && !(stored && stored[s].bytes)) return true;
  return false;
}

}  // namespace

double GpuKernelTiming::median() const {
  if (ms.empty()) return 0;
  std::vector<double> v = ms;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

uint64_t GpuRenderer::slotFloats(const FrameSlot& slot) { return slotFloatCount(slot); }

uint64_t GpuRenderer::defaultSlotKey(const FrameSlot& slot) {
  // The fields that tell two models apart, through the project's one hash (hash.hpp).
  uint64_t h = fnv1a64(&slot.kind, sizeof slot.kind);
  h = fnv1a64(&slot.level, sizeof slot.level, h);
  for (int a = 0; a < 3; ++a) {
    h = fnv1a64(&slot.lo[a], sizeof slot.lo[a], h);
    h = fnv1a64(&slot.invExtent[a], sizeof slot.invExtent[a], h);
    h = fnv1a64(&slot.knots[a].ncp, sizeof slot.knots[a].ncp, h);
    h = fnv1a64(&slot.knots[a].degree, sizeof slot.knots[a].degree, h);
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
  float* deviceLimits = nullptr;  // ray length limits from a device depth buffer
  size_t limitsCapacity = 0;      // pixels
  cudaEvent_t events[4] = {nullptr, nullptr, nullptr, nullptr};
  // DS baseline through 3D textures: one CUDA array + texture object per raw model, kept across
  // frames (no budget: a benchmark baseline), and this frame's handles in slot order.
  struct Texture {
    cudaArray_t array = nullptr;
    cudaTextureObject_t object = 0;
  };
  std::unordered_map<uint64_t, Texture> textures;
  unsigned long long* hostHandles = nullptr;
  unsigned long long* deviceHandles = nullptr;
  size_t handleCapacity = 0;

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
    if (deviceLimits) (void)cudaFree(deviceLimits);
    deviceLimits = nullptr;
    limitsCapacity = 0;
    for (auto& t : textures) {
      if (t.second.object) (void)cudaDestroyTextureObject(t.second.object);
      if (t.second.array) (void)cudaFreeArray(t.second.array);
    }
    textures.clear();
    if (hostHandles) (void)cudaFreeHost(hostHandles);
    if (deviceHandles) (void)cudaFree(deviceHandles);
    hostHandles = deviceHandles = nullptr;
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

  /// Ray length limits of `pixels` pixels from depth.depth into deviceLimits (row 0 = top), their
  /// count into deviceCounter, on the stream.
  void depthLimits(const DeviceDepth& depth, size_t pixels) {
    if (pixels > limitsCapacity) {
      AFAM_CUDA_CHECK(cudaStreamSynchronize(stream));
      if (deviceLimits) AFAM_CUDA_CHECK(cudaFree(deviceLimits));
      deviceLimits = nullptr;
      limitsCapacity = 0;
      AFAM_CUDA_CHECK(cudaMalloc(reinterpret_cast<void**>(&deviceLimits), pixels * sizeof(float)));
      limitsCapacity = pixels;
    }
    AFAM_CUDA_CHECK(cudaMemsetAsync(deviceCounter, 0, 8, stream));
    kernels_depth::launchDepthLimits(depth.toRay, depth.depth, deviceLimits, deviceCounter, stream);
    AFAM_CUDA_CHECK(cudaGetLastError());
  }

  int64_t limitedCount() {
    unsigned long long count = 0;
    AFAM_CUDA_CHECK(cudaMemcpyAsync(&count, deviceCounter, 8, cudaMemcpyDeviceToHost, stream));
    AFAM_CUDA_CHECK(cudaStreamSynchronize(stream));
    return int64_t(count);
  }

  /// Texture handles of this frame's raw slots on the device (creating missing textures; the
  /// copies into CUDA arrays are synchronous: this is the baseline, not the product path).
  const unsigned long long* textureHandles(const FrameView& v, const uint64_t* keys) {
    if (v.slotCount > 0 && !v.pool)
      throw InvalidArgument("GpuRenderer: the 3D-texture DS path reads the frame's host pool");
    const size_t n = size_t(std::max(v.slotCount, 1));
    if (n > handleCapacity) {
      AFAM_CUDA_CHECK(cudaStreamSynchronize(stream));
      if (hostHandles) AFAM_CUDA_CHECK(cudaFreeHost(hostHandles));
      if (deviceHandles) AFAM_CUDA_CHECK(cudaFree(deviceHandles));
      hostHandles = deviceHandles = nullptr;
      handleCapacity = 0;
      AFAM_CUDA_CHECK(cudaMallocHost(reinterpret_cast<void**>(&hostHandles), n * 8));
      AFAM_CUDA_CHECK(cudaMalloc(reinterpret_cast<void**>(&deviceHandles), n * 8));
      handleCapacity = n;
    }
    AFAM_CUDA_CHECK(cudaStreamSynchronize(stream));
    for (int32_t s = 0; s < v.slotCount; ++s) {
      const FrameSlot& slot = v.slots[s];
      if (slot.kind != kSlotRaw)
        throw InvalidArgument("GpuRenderer: the 3D-texture DS path needs raw (DS) slots only");
      const uint64_t key = keys ? keys[s] : GpuRenderer::defaultSlotKey(slot);
      auto it = textures.find(key);
      if (it == textures.end()) {
        Texture t;
        const cudaExtent extent = make_cudaExtent(
            size_t(slot.knots[0].ncp), size_t(slot.knots[1].ncp), size_t(slot.knots[2].ncp));
        const cudaChannelFormatDesc desc = cudaCreateChannelDesc<float>();
        AFAM_CUDA_CHECK(cudaMalloc3DArray(&t.array, &desc, extent));
        cudaMemcpy3DParms copy{};
        copy.srcPtr =
            make_cudaPitchedPtr(const_cast<float*>(v.pool + slot.offset),
                                extent.width * sizeof(float), extent.width, extent.height);
        copy.dstArray = t.array;
        copy.extent = extent;
        copy.kind = cudaMemcpyHostToDevice;
        AFAM_CUDA_CHECK(cudaMemcpy3D(&copy));
        cudaResourceDesc res{};
        res.resType = cudaResourceTypeArray;
        res.res.array.array = t.array;
        cudaTextureDesc td{};
        for (auto& mode : td.addressMode) mode = cudaAddressModeClamp;
        td.filterMode = cudaFilterModeLinear;
        td.readMode = cudaReadModeElementType;
        td.normalizedCoords = 0;
        AFAM_CUDA_CHECK(cudaCreateTextureObject(&t.object, &res, &td, nullptr));
        it = textures.emplace(key, t).first;
      }
      hostHandles[s] = (unsigned long long)it->second.object;
    }
    AFAM_CUDA_CHECK(cudaMemcpyAsync(deviceHandles, hostHandles, size_t(v.slotCount) * 8,
                                    cudaMemcpyHostToDevice, stream));
    return deviceHandles;
  }

  /// Whether the frame's models as float32 would take more than three quarters of the pool: the
  /// pool is under pressure (GpuPoolModels::Auto then keeps compact models compact). Below that,
  /// evicting older frames' models costs fewer uploads than the kernels reading codes cost time.
  bool underPressure(const FrameView& v) const {
    size_t floatBytes = 0;
    for (int32_t s = 0; s < v.slotCount; ++s)
      floatBytes += align256(size_t(expandedFloats(v.slots[s])) * sizeof(float));
    return floatBytes > pool.ledger().stats().capacityBytes / 4 * 3;
  }

  /// Makes `slot`'s model resident (uploaded, or its stored payload queued for decoding, where it
  /// is not) and sets its offset. A compact model is expanded into float32 points unless the pool
  /// holds it compact already or `how` asks for compact models (Compact: even one resident as
  /// floats; Auto under pressure: one not resident yet); both forms give the kernels the same
  /// floats. Returns whether the slot now reads codes.
  bool place(FrameSlot& slot, uint64_t key, const float* host, const GpuStoredSlot* stored,
             GpuPoolModels how) {
    const CompactForm form{slot.codeWidth, slot.codeTable};
    const size_t floatBytes = size_t(expandedFloats(slot)) * sizeof(float);
    const size_t codedBytes = size_t(slotFloats(slot)) * sizeof(float);  // floatBytes if width 0
    const size_t resident = pool.ledger().residentBytes(key);
    const bool keepCodes = !stored && form.width > 0 &&
                           (resident == codedBytes || how == GpuPoolModels::Compact ||
                            (how == GpuPoolModels::Auto && resident != floatBytes));
    if (!keepCodes) {
      slot.codeWidth = 0;
      slot.codeTable = 0;
    }
    size_t byteOffset = 0;
    if (stored)
      byteOffset =
          pool.acquireStored(key, stored->bytes, stored->storedBytes, floatBytes, stored->job);
    else if (keepCodes || form.width == 0)  // the host's floats or codes as they are
      byteOffset = pool.acquire(key, host, codedBytes);
    else
      byteOffset = pool.acquireCompact(
          key, host, form, {slot.knots[0].ncp, slot.knots[1].ncp, slot.knots[2].ncp}, floatBytes);
    slot.offset = byteOffset / sizeof(float);
    return keepCodes;
  }

  /// Makes every slot's model resident, uploads the frame tables and returns the device view
  /// (*compactSlots: how many of its slots read codes). All copies are queued on `stream`;
  /// kernels queued after it see the data.
  FrameView upload(const FrameView& v, const uint64_t* keys, GpuPoolModels how,
                   int64_t* compactSlots, uint64_t* modelsUploaded, uint64_t* bytesUploaded,
                   const float* const* slotHost = nullptr, const GpuStoredSlot* stored = nullptr) {
    if (v.camera.width < 1 || v.camera.height < 1)
      throw InvalidArgument("GpuRenderer: image size " + std::to_string(v.camera.width) + " x " +
                            std::to_string(v.camera.height) + " is empty");
    if (v.slotCount > 0 && (!v.slots || (!v.pool && !slotHost)))
      throw InvalidArgument("GpuRenderer: frame has slots but no slot table or model floats");
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
    const size_t pixels = size_t(v.camera.width) * size_t(v.camera.height);
    const size_t depthOffset = size;  // optional per-pixel ray length limit (opaque geometry)
    if (v.maxDistance) size = align256(size + sizeof(float) * pixels);
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
    if (v.maxDistance) std::memcpy(hostTables + depthOffset, v.maxDistance, sizeof(float) * pixels);
    auto* slots = reinterpret_cast<FrameSlot*>(hostTables + slotOffset);
    if (how == GpuPoolModels::Auto && !underPressure(v)) how = GpuPoolModels::Floats;
    int64_t coded = 0;
    for (int32_t s = 0; s < v.slotCount; ++s) {
      FrameSlot slot = v.slots[s];
      if (slotFloats(slot) == 0) {  // an empty block: nothing to hold
        slots[s] = slot;
        continue;
      }
      const uint64_t key = keys ? keys[s] : defaultSlotKey(slot);
      const bool decode = stored && stored[s].bytes;
      const float* host = decode ? nullptr : slotHost ? slotHost[s] : v.pool + slot.offset;
      coded += place(slot, key, host, decode ? &stored[s] : nullptr, how);
      slots[s] = slot;
    }
    if (compactSlots) *compactSlots = coded;
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
    d.maxDistance =
        v.maxDistance ? reinterpret_cast<const float*>(deviceTables + depthOffset) : nullptr;
    d.pool = static_cast<const float*>(pool.arena());
    d.slotData = nullptr;  // host pointers: the models are in the pool
    return d;
  }
};

namespace {

std::string launchFull(GpuFloatMode m, bool shaded, int p, const FrameView& d, float* image,
                       cudaStream_t s, bool describe, int minBlocks, bool codes) {
  switch (m) {
    case GpuFloatMode::Fma:
      return kernels_fma::launchFull(shaded, p, d, image, s, describe, minBlocks, codes);
    case GpuFloatMode::Fast:
      return kernels_fast::launchFull(shaded, p, d, image, s, describe, minBlocks, codes);
    default:
      return kernels_exact::launchFull(shaded, p, d, image, s, describe, minBlocks, codes);
  }
}
void launchCount(GpuFloatMode m, bool shaded, int p, const FrameView& d, unsigned long long* total,
                 cudaStream_t s, bool codes) {
  switch (m) {
    case GpuFloatMode::Fma:
      return kernels_fma::launchCount(shaded, p, d, total, s, codes);
    case GpuFloatMode::Fast:
      return kernels_fast::launchCount(shaded, p, d, total, s, codes);
    default:
      return kernels_exact::launchCount(shaded, p, d, total, s, codes);
  }
}
std::string launchBare(GpuFloatMode m, int p, const FrameView& d, float* sink,
                       unsigned long long* total, cudaStream_t s, bool describe, bool codes) {
  switch (m) {
    case GpuFloatMode::Fma:
      return kernels_fma::launchBare(p, d, sink, total, s, describe, codes);
    case GpuFloatMode::Fast:
      return kernels_fast::launchBare(p, d, sink, total, s, describe, codes);
    default:
      return kernels_exact::launchBare(p, d, sink, total, s, describe, codes);
  }
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
                         GpuFrameTimes* times, const float* const* slotHost,
                         const GpuStoredSlot* stored) {
  cast(view, slotKeys, nullptr, rgba, times, nullptr, slotHost, stored);
}

void GpuRenderer::renderToDevice(const FrameView& view, const uint64_t* slotKeys, float* deviceRgba,
                                 GpuFrameTimes* times, const DeviceDepth* depth,
                                 const float* const* slotHost, const GpuStoredSlot* stored) {
  if (!deviceRgba) throw InvalidArgument("renderToDevice: no device image");
  cast(view, slotKeys, deviceRgba, nullptr, times, depth && depth->depth ? depth : nullptr,
       slotHost, stored);
}

namespace {
void checkDepthSize(const DeviceDepth& depth, int width, int height) {
  const DepthToRay& t = depth.toRay;
  if (t.width != width || t.height != height || t.tileWidth < t.width || t.tileHeight < t.height)
    throw InvalidArgument("GpuRenderer: depth limits for a " + std::to_string(t.width) + " x " +
                          std::to_string(t.height) + " image from a " +
                          std::to_string(t.tileWidth) + " x " + std::to_string(t.tileHeight) +
                          " tile, for a " + std::to_string(width) + " x " + std::to_string(height) +
                          " frame");
}
}  // namespace

int64_t GpuRenderer::depthLimitsToHost(const DeviceDepth& depth, std::vector<float>& limits) {
  Impl& m = *impl_;
  checkDepthSize(depth, depth.toRay.width, depth.toRay.height);
  const size_t pixels = size_t(depth.toRay.width) * size_t(depth.toRay.height);
  m.depthLimits(depth, pixels);
  limits.resize(pixels);
  AFAM_CUDA_CHECK(cudaMemcpyAsync(limits.data(), m.deviceLimits, pixels * sizeof(float),
                                  cudaMemcpyDeviceToHost, m.stream));
  return m.limitedCount();
}

void GpuRenderer::cast(const FrameView& view, const uint64_t* slotKeys, float* deviceTarget,
                       float* hostRgba, GpuFrameTimes* times, const DeviceDepth* depth,
                       const float* const* slotHost, const GpuStoredSlot* stored) {
  if (simulateFailure_)
    throw GpuError("CUDA error cudaErrorContextIsDestroyed (709): simulated loss of the context",
                   __FILE__, __LINE__, "cudaErrorContextIsDestroyed", 709);
  Impl& m = *impl_;
  lastTimes_ = GpuFrameTimes{};
  lastCompactSlots_ = 0;
  const size_t pixels = size_t(view.camera.width) * size_t(view.camera.height);
  if (pixels > 0 && !deviceTarget) m.reserveImage(pixels);
  float* target = deviceTarget ? deviceTarget : reinterpret_cast<float*>(m.deviceImage);
  AFAM_CUDA_CHECK(cudaEventRecord(m.events[0], m.stream));
  GpuFrameTimes t;
  int64_t compactSlots = 0;
  const PoolStats before = m.pool.stats();
  FrameView d;
  try {
    d = m.upload(view, slotKeys, poolModels_, &compactSlots, &t.modelsUploaded, &t.bytesUploaded,
                 slotHost, stored);
  } catch (const GpuOutOfMemory&) {
    // Its models did not fit together: once more with every compact model compact, those
    // resident as floats too, before the caller gives the frame to the CPU (a frame with none,
    // e.g. of models the GPU decodes, goes there at once).
    if (poolModels_ != GpuPoolModels::Auto || !hasCompactModels(view, stored)) throw;
    d = m.upload(view, slotKeys, GpuPoolModels::Compact, &compactSlots, nullptr, nullptr, slotHost,
                 stored);
    t.modelsUploaded = m.pool.stats().uploads - before.uploads;
    t.bytesUploaded = m.pool.stats().bytesUploaded - before.bytesUploaded;
  }
  if (depth) {  // the limits come from the device depth, not from view.maxDistance
    checkDepthSize(*depth, view.camera.width, view.camera.height);
    m.depthLimits(*depth, pixels);
    d.maxDistance = m.deviceLimits;
  }
  AFAM_CUDA_CHECK(cudaEventRecord(m.events[1], m.stream));
  if (poison_) AFAM_CUDA_CHECK(cudaMemsetAsync(target, 0xFF, pixels * sizeof(float4), m.stream));
  const int p = specialise_ ? uniformDegree(view) : -1;
  if (dsTextures_ && view.blendMode == kBlendComposite)  // the texture kernel composites only
    kernelInfo_ = kernels_texture::launchDsTexture(
        view.shading != 0, d, m.textureHandles(view, slotKeys), target, nullptr, m.stream, true);
  else
    kernelInfo_ = launchFull(mode_, view.shading != 0, p, d, target, m.stream, true, minBlocks_,
                             compactSlots > 0);
  AFAM_CUDA_CHECK(cudaEventRecord(m.events[2], m.stream));
  if (hostRgba)  // else the image stays where the caller's device pointer says
    AFAM_CUDA_CHECK(cudaMemcpyAsync(m.hostImage, m.deviceImage, pixels * sizeof(float4),
                                    cudaMemcpyDeviceToHost, m.stream));
  AFAM_CUDA_CHECK(cudaEventRecord(m.events[3], m.stream));
  AFAM_CUDA_CHECK(cudaEventSynchronize(m.events[3]));
  if (hostRgba) std::memcpy(hostRgba, m.hostImage, pixels * sizeof(float4));
  t.depthLimitedPixels = depth ? m.limitedCount() : -1;
  t.uploadMs = elapsed(m.events[0], m.events[1]);
  t.kernelMs = elapsed(m.events[1], m.events[2]);
  t.downloadMs = hostRgba ? elapsed(m.events[2], m.events[3]) : 0.0;
  t.totalMs = elapsed(m.events[0], m.events[3]);
  lastTimes_ = t;
  lastCompactSlots_ = compactSlots;
  if (times) *times = t;
}

GpuKernelTiming GpuRenderer::timeKernel(const FrameView& view, const uint64_t* slotKeys,
                                        GpuKernelKind kind, int repetitions) {
  Impl& m = *impl_;
  const size_t pixels = size_t(view.camera.width) * size_t(view.camera.height);
  m.reserveImage(pixels);
  int64_t compactSlots = 0;
  const FrameView d = m.upload(view, slotKeys, poolModels_, &compactSlots, nullptr, nullptr);
  const bool codes = compactSlots > 0;
  const int p = specialise_ ? uniformDegree(view) : -1;
  const bool shaded = view.shading != 0;
  auto* sink = reinterpret_cast<float*>(m.deviceImage);
  GpuKernelTiming timing;
  // Untimed launch that counts the evaluated samples.
  AFAM_CUDA_CHECK(cudaMemsetAsync(m.deviceCounter, 0, 8, m.stream));
  const unsigned long long* handles =
      dsTextures_ && kind == GpuKernelKind::Full ? m.textureHandles(view, slotKeys) : nullptr;
  if (handles)
    (void)kernels_texture::launchDsTexture(shaded, d, handles, sink, m.deviceCounter, m.stream,
                                           false);
  else if (kind == GpuKernelKind::Full)
    launchCount(mode_, shaded, p, d, m.deviceCounter, m.stream, codes);
  else
    (void)launchBare(mode_, p, d, sink, m.deviceCounter, m.stream, false, codes);
  unsigned long long count = 0;
  AFAM_CUDA_CHECK(cudaMemcpyAsync(&count, m.deviceCounter, 8, cudaMemcpyDeviceToHost, m.stream));
  AFAM_CUDA_CHECK(cudaStreamSynchronize(m.stream));
  timing.samples = count;
  for (int r = -1; r < repetitions; ++r) {  // r = -1: warm-up
    AFAM_CUDA_CHECK(cudaEventRecord(m.events[0], m.stream));
    const std::string info =
        handles
            ? kernels_texture::launchDsTexture(shaded, d, handles, sink, nullptr, m.stream, r == -1)
        : kind == GpuKernelKind::Full
            ? launchFull(mode_, shaded, p, d, sink, m.stream, r == -1, minBlocks_, codes)
            : launchBare(mode_, p, d, sink, nullptr, m.stream, r == -1, codes);
    if (r == -1) kernelInfo_ = info;
    AFAM_CUDA_CHECK(cudaEventRecord(m.events[1], m.stream));
    AFAM_CUDA_CHECK(cudaEventSynchronize(m.events[1]));
    if (r >= 0) timing.ms.push_back(elapsed(m.events[0], m.events[1]));
  }
  return timing;
}

}  // namespace afam
