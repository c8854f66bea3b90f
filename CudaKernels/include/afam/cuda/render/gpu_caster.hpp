// SPDX-License-Identifier: BSD-3-Clause
// The CUDA ray caster as a Renderer's FrameCaster (Renderer::setCaster): caching, LOD, culling and
// prefetching stay the Renderer's; only the casting of a prepared frame runs on the GPU. It owns
// the GPU renderer, its model pool and its stream; each frame's targets (a device image, a device
// depth) come with that frame. Front ends make it through makeGpuCaster (make_gpu_caster.hpp);
// tests and benchmarks that look inside use GpuCaster::create. Plain C++: no CUDA header.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <unordered_set>

#include "afam/cuda/decode/gpu_model_pool.hpp"
#include "afam/cuda/render/gpu_renderer.hpp"
#include "afam/cuda/render/make_gpu_caster.hpp"
#include "afam/render/frame_caster.hpp"

namespace afam {

class GpuCaster : public FrameCaster {
 public:
  /// What makeGpuCaster does, with the concrete type: probes for a usable device, takes this
  /// process's (gpuChoice for an OpenGL context on `openGl`) and allocates a model pool of
  /// `budgetBytes`, halving down to 16 MiB while device memory is short. Returns nullptr, every
  /// reason given to `report`, when no GPU is usable.
  static std::unique_ptr<GpuCaster> create(size_t budgetBytes, int threads, const GpuReport& report,
                                           const std::optional<DeviceUuid>& openGl = {});
  ~GpuCaster() override;

  /// Casts on the GPU into targets.deviceRgba when given and large enough (nothing comes back to
  /// the host), else into `image`; device depth limits computed on the GPU (brought to the host
  /// for a frame cast on the CPU). A frame whose models exceed the pool is cast on the CPU (said
  /// once); a frame whose CUDA work fails otherwise is cast on the CPU, and so is every later
  /// frame (failed(), said once). Never throws for a full or failing GPU.
  CastResult cast(const PreparedFrame& frame, const FrameTargets& targets,
                  ImageRGBA& image) override;
  bool castsOnGpu() const override { return !failed_; }
  /// The cudaStream_t of the pool and the kernels.
  void* deviceStream() const override { return stream(); }
  /// "NVIDIA H200 (sm_90, ...), CUDA device 1: local rank 1's own GPU".
  std::string description() const override { return description_; }
  /// Reads the cached models (PreparedFrame::slotHost): the pool copies only those not resident,
  /// a compact one expanded to float32 points or kept compact (GpuRenderer::setPoolModels; the
  /// environment's AFAM_GPU_POOL_MODELS=auto|floats|compact for benchmarks).
  bool readsHostPool() const override { return false; }
  /// The models the GPU decodes (gpuDecodesEntry), while it works: the cache keeps them as their
  /// stored payloads, and a miss costs the copy of its compressed bytes and a decoding kernel.
  StoredForm storedForm() const override;
  /// Off: every model is decoded on the CPU and uploaded as floats (the default is on, unless
  /// the environment sets AFAM_GPU_DECODE=0; benchmarks compare both).
  void setDecodeOnGpu(bool on) { decodeOnGpu_ = on; }

  void* stream() const;
  /// True once a frame's CUDA work failed for another reason than memory (e.g. a lost context).
  bool failed() const { return failed_; }
  const PoolStats& poolStats() const;
  /// The GPU's times of the last frame cast on it (all zero when it did not finish).
  const GpuFrameTimes& lastTimes() const;
  /// The renderer itself (tests: simulated failures, poisoned output).
  GpuRenderer& gpu() { return *gpu_; }

 private:
  GpuCaster(std::unique_ptr<GpuRenderer> gpu, int threads);
  /// The frame's models the GPU's decoder refused (CastResult::damaged); one the CPU decodes (an
  /// interpolant whose residuals the GPU cannot hold, 2^31 steps or more: hand-made payloads only,
  /// the encoder writes none) is not damaged: from the next frame on it is decoded on the CPU
  /// (hostDecodes_).
  void reportDecodeFailures(const PreparedFrame& frame, CastResult& result);
  std::unique_ptr<GpuRenderer> gpu_;
  int threads_;
  std::string description_;
  bool warned_ = false;      ///< a frame too large for the pool was reported
  bool decodeOnGpu_ = true;  ///< AFAM_GPU_DECODE=0 turns it off (benchmarks: the CPU's decoding)
  std::unordered_set<uint64_t> hostDecodes_;  ///< cache keys of models the CPU decodes for the GPU
  bool failed_ = false;
};

}  // namespace afam
