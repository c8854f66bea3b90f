// SPDX-License-Identifier: BSD-3-Clause
#include "afam/cuda/render/gpu_caster.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <string>
#include <vector>

#include "afam/cuda/decode/gpu_block_decoder.hpp"
#include "afam/ranks/device_selection.hpp"
#include "afam/render/cpu_raycaster.hpp"
#include "afam/render/prepared_frame.hpp"

namespace afam {

std::unique_ptr<GpuCaster> GpuCaster::create(size_t budgetBytes, int threads,
                                             const GpuReport& report,
                                             const std::optional<DeviceUuid>& openGl) {
  std::string why;
  if (!gpuAvailable(&why, openGl)) {
    report("no usable GPU: " + why);
    return nullptr;
  }
  // One GPU per MPI rank on a node with several, the OpenGL context's where it can be
  // (device_selection.hpp); the description says which and why.
  const GpuChoice choice = gpuChoice(openGl);
  const int device = choice.device;
  std::unique_ptr<GpuRenderer> gpu;
  // What was asked for, halved while the device has no room for it, down to 16 MiB.
  const size_t minBudget = std::min(budgetBytes, size_t(16) << 20);
  for (size_t budget = budgetBytes; !gpu && budget >= minBudget && budget > 0; budget /= 2) {
    try {
      gpu = std::make_unique<GpuRenderer>(budget, device);
    } catch (const GpuOutOfMemory& e) {
      report("GPU pool of " + std::to_string(budget >> 20) + " MiB: " + e.what() + "; trying half");
    } catch (const GpuError& e) {
      report(std::string("GPU unusable: ") + e.what());
      return nullptr;
    }
  }
  if (!gpu) {
    report("no GPU memory for a model pool");
    return nullptr;
  }
  auto caster = std::unique_ptr<GpuCaster>(new GpuCaster(std::move(gpu), threads));
  caster->description_ += ", CUDA device " + std::to_string(device) + ": " + choice.why;
  return caster;
}

std::unique_ptr<FrameCaster> makeGpuCaster(size_t budgetBytes, int threads, const GpuReport& report,
                                           const std::optional<DeviceUuid>& openGl) {
  return GpuCaster::create(budgetBytes, threads, report, openGl);
}

bool gpuCasterBuilt() { return true; }

GpuCaster::GpuCaster(std::unique_ptr<GpuRenderer> gpu, int threads)
    : gpu_(std::move(gpu)), threads_(threads), description_(gpuDescription(gpu_->pool().device())) {
  const char* decode = std::getenv("AFAM_GPU_DECODE");
  decodeOnGpu_ = !(decode && std::strcmp(decode, "0") == 0);
  // Benchmarks: how the pool holds compact models (GpuPoolModels; default auto).
  if (const char* env = std::getenv("AFAM_GPU_POOL_MODELS")) {
    const std::string how = env;
    if (how == "floats")
      gpu_->setPoolModels(GpuPoolModels::Floats);
    else if (how == "compact")
      gpu_->setPoolModels(GpuPoolModels::Compact);
    else if (how != "auto")
      std::fprintf(stderr,
                   "afam: AFAM_GPU_POOL_MODELS is '%s', not auto, floats or compact: auto\n", env);
  }
}

StoredForm GpuCaster::storedForm() const {
  return failed_ || !decodeOnGpu_ ? nullptr : &gpuDecodesEntry;
}

namespace {

/// What the GPU is given of a frame's models: stored payloads it decodes (stored[s].bytes set),
/// and floats or compact models (host[s]; the pool expands a compact one into its staging memory
/// when it is not resident); a model in the stored form that the GPU's decoder does not take is
/// decoded here (NaN and reported in `damaged` where it does not decode), as are those the GPU
/// refused before and the CPU decodes (`onHost`, cache keys).
struct FrameModels {
  std::vector<GpuStoredSlot> stored;
  std::vector<const float*> host;
  std::deque<std::vector<float>> decodedHere;  // stable addresses

  FrameModels(const PreparedFrame& frame, CastResult& result,
              const std::unordered_set<uint64_t>& onHost)
      : host(frame.slotHost) {
    for (size_t s = 0; s < frame.models.size(); ++s) {
      const CachedModel& m = *frame.models[s];
      if (!m.isStored()) continue;
      const ModelEntry& e = *frame.slotEntries[s];
      if (stored.empty()) stored.resize(frame.models.size());
      const bool refused = s < frame.keys.size() && onHost.count(frame.keys[s]);
      if (!refused && gpuDecodable(e, m.stored.data())) {
        stored[s] =
            GpuStoredSlot{m.stored.data(), m.stored.size(), gpuDecodeJob(e, m.stored.data(), 0, 0)};
        continue;
      }
      std::vector<float>& out = decodedHere.emplace_back(frame.slotFloats(s));
      const std::string damage = frame.writeSlot(s, out.data());
      if (!damage.empty()) result.damaged.push_back({frame.entries[s], damage});
      host[s] = out.data();
    }
  }
  const GpuStoredSlot* storedSlots() const { return stored.empty() ? nullptr : stored.data(); }
};

}  // namespace

GpuCaster::~GpuCaster() = default;

void* GpuCaster::stream() const { return gpu_->pool().stream(); }

const PoolStats& GpuCaster::poolStats() const { return gpu_->pool().stats(); }

const GpuFrameTimes& GpuCaster::lastTimes() const { return gpu_->lastTimes(); }

namespace {

/// Whether slot s's stored model, refused by the GPU, is one the CPU decodes (an interpolant with
/// a residual beyond the GPU's 32 bits; the GPU and the CPU refuse damaged payloads alike).
bool decodesOnHost(const PreparedFrame& frame, size_t s) {
  if (s >= frame.models.size() || !frame.models[s]->isStored()) return false;
  std::vector<float> out(frame.slotFloats(s));
  return frame.writeSlot(s, out.data()).empty();
}

}  // namespace

void GpuCaster::reportDecodeFailures(const PreparedFrame& frame, CastResult& result) {
  for (const auto& [key, status] : gpu_->pool().takeDecodeFailures())
    for (size_t s = 0; s < frame.keys.size() && s < frame.entries.size(); ++s) {
      if (frame.keys[s] != key) continue;
      if (decodesOnHost(frame, s)) {
        hostDecodes_.insert(key);  // drawn from the next frame on
        continue;
      }
      result.damaged.push_back({frame.entries[s], std::string("payload does not decode (") +
                                                      gpuDecodeStatusText(status) + ")"});
    }
}

CastResult GpuCaster::cast(const PreparedFrame& frame, const FrameTargets& targets,
                           ImageRGBA& image) {
  CastResult result;
  const int w = frame.view.camera.width, h = frame.view.camera.height;
  const size_t floats = size_t(w) * size_t(h) * 4;
  FrameView view = frame.view;
  view.maxDistance = targets.maxDistance;
  std::vector<float> pool;  // the models side by side, only for a frame cast on the CPU after all
  auto castOnCpu = [&] {
    view = frame.hostView(pool);
    view.maxDistance = targets.maxDistance;
    image.resize(w, h);
    renderCpu(view, image, threads_);
  };
  if (failed_) {  // known to fail: not tried again, and the device depth is not read
    castOnCpu();
    return result;
  }
  // The cached models themselves: the pool copies (or decodes) only those it does not hold yet.
  const FrameModels models(frame, result, hostDecodes_);
  const float* const* slotHost =
      models.host.size() == size_t(frame.view.slotCount) ? models.host.data() : nullptr;
  const uint64_t* slotKeys =
      frame.keys.size() == size_t(frame.view.slotCount) ? frame.keys.data() : nullptr;
  const bool onDevice = targets.deviceRgba && floats <= targets.deviceRgbaFloats;
  const DeviceDepth* depth = targets.deviceDepth.depth ? &targets.deviceDepth : nullptr;
  const uint64_t uploadsBefore = poolStats().uploads;
  std::vector<float> hostLimits;
  auto limitsOnHost = [&] {  // a frame whose image goes through the host
    if (!depth) return;
    result.depthLimitedPixels = gpu_->depthLimitsToHost(*depth, hostLimits);
    view.maxDistance = hostLimits.data();
  };
  try {
    if (onDevice) {
      gpu_->renderToDevice(view, slotKeys, targets.deviceRgba, nullptr, depth, slotHost,
                           models.storedSlots());
      result.depthLimitedPixels = gpu_->lastTimes().depthLimitedPixels;
      image.width = w;
      image.height = h;
      image.rgba.clear();
      result.imageOnDevice = true;
    } else {
      limitsOnHost();
      image.resize(w, h);
      gpu_->render(view, slotKeys, image.rgba.data(), nullptr, slotHost, models.storedSlots());
    }
    result.onGpu = true;
    reportDecodeFailures(frame, result);
    const GpuFrameTimes& t = gpu_->lastTimes();
    if (t.totalMs > 0) {
      result.gpuUploadMs = t.uploadMs;
      result.gpuKernelMs = t.kernelMs;
      result.gpuDownloadMs = t.downloadMs;
    }
  } catch (const GpuOutOfMemory& e) {
    if (!warned_) result.messages.push_back(std::string(e.what()) + "; this frame on the CPU");
    warned_ = true;
    if (hostLimits.empty()) limitsOnHost();
    castOnCpu();
  } catch (const GpuError& e) {
    failed_ = true;
    result.messages.push_back(std::string("the GPU failed (") + e.what() +
                              "); this frame and the next ones on the CPU");
    castOnCpu();
  }
  if (!failed_) result.modelsUploaded = int64_t(poolStats().uploads - uploadsBefore);
  return result;
}

}  // namespace afam
