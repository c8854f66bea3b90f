// SPDX-License-Identifier: BSD-3-Clause
// The CUDA ray caster behind a plain C++ interface (no CUDA header here).
//
// The caller builds a FrameView exactly as for the CPU ray caster (host pointers); render() uploads
// the models that the GPU model pool does not hold yet, the per-frame indirection grid, slot table
// and transfer function, launches one thread per pixel calling the shared afam::castRay<Shaded>
// (raycast.hpp), and copies the premultiplied RGBA image back. CPU and GPU run the same math.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "afam/cuda/common/gpu_error.hpp"
#include "afam/cuda/decode/gpu_model_pool.hpp"
#include "afam/render/frame_caster.hpp"  // DeviceDepth
#include "afam/render/raycast.hpp"

namespace afam {

/// Times of one render() call, milliseconds from CUDA events on the renderer's stream.
struct GpuFrameTimes {
  double uploadMs = 0;  ///< models not yet resident + frame tables
  double kernelMs = 0;
  double downloadMs = 0;  ///< image back to the host
  double totalMs = 0;
  uint64_t modelsUploaded = 0;
  uint64_t bytesUploaded = 0;
  int64_t depthLimitedPixels = -1;  ///< pixels a DeviceDepth limited; -1: none given
};

enum class GpuKernelKind {
  Full,              ///< castRay<Shaded>: lookup, value(+gradient), TF, Phong, compositing
  BareValueGradient  ///< baseline: lookup + value + gradient at every sample of the same rays
};

/// Floating-point contract of the kernels.
enum class GpuFloatMode {
  Exact,  ///< no FMA contraction, IEEE division/sqrt: the CPU caster's roundings (default)
  Fma,    ///< nvcc's default: multiply-adds contracted to FMA
  Fast    ///< -use_fast_math: FMA, approximate division, sqrt and powf
};

/// How the pool holds a model the frame gives in its compact form (FrameSlot::codeWidth: a table
/// and a 1- or 2-byte code a point), which the kernels read as the same floats either way.
enum class GpuPoolModels {
  /// Expanded to float32 while the frame's models as float32 take at most three quarters of the
  /// pool; compact beyond (the pool under pressure holds 2-4x more models, and frames with a
  /// compact model launch the kernels that read codes, 8% slower); a frame whose models do not
  /// fit together is placed again with every compact model compact. Default.
  Auto,
  Floats,  ///< always expanded (the faster kernels; a pool holding fewer models)
  Compact  ///< always compact
};

/// Result of timeKernel(): per-launch milliseconds and the number of model evaluations per launch.
struct GpuKernelTiming {
  std::vector<double> ms;
  uint64_t samples = 0;  ///< evaluated samples per launch (counted in a separate, untimed launch)
  double median() const;
};

/// A slot whose model the pool decodes on the GPU from its stored payload
/// (GpuModelPool::acquireStored) when it is not resident.
struct GpuStoredSlot {
  const uint8_t* bytes = nullptr;  ///< null: the slot's model is floats (slotHost or view.pool)
  size_t storedBytes = 0;
  GpuDecodeJob job;  ///< gpuDecodeJob's kind and NCP
};

class GpuRenderer {
 public:
  /// poolBudgetBytes: device memory for resident models. Throws GpuOutOfMemory / GpuError.
  explicit GpuRenderer(size_t poolBudgetBytes, int device = 0);
  ~GpuRenderer();
  GpuRenderer(const GpuRenderer&) = delete;
  GpuRenderer& operator=(const GpuRenderer&) = delete;

  /// Renders `view` (host pointers; castRay<true> when view.shading != 0) into `rgba`
  /// (width*height*4 floats, premultiplied, row 0 at the top, as castRay returns it).
  /// slotKeys[s] names slot s's model across frames (nullptr: a key derived from its kind, level,
  /// extent and size). Throws GpuOutOfMemory when the frame's models exceed the pool budget.
  /// slotHost (optional): slot s's floats at slotHost[s] on the host instead of view.pool +
  /// offset (a frame that references cached models, copied only when not resident here).
  /// stored (optional): slot s's model as its stored payload where stored[s].bytes is set, decoded
  /// on the GPU when not resident (GpuModelPool::takeDecodeFailures tells which did not decode).
  void render(const FrameView& view, const uint64_t* slotKeys, float* rgba,
              GpuFrameTimes* times = nullptr, const float* const* slotHost = nullptr,
              const GpuStoredSlot* stored = nullptr);
  /// As render(), but the image is cast into `deviceRgba` (device memory of width*height*4
  /// floats, e.g. an OpenGL buffer mapped into CUDA) and left there: nothing comes back to the
  /// host (downloadMs 0). The caller keeps `deviceRgba` valid until the call returns.
  /// `depth` (optional): per-pixel ray limits computed on the GPU from a device depth buffer
  /// (rayLimitFromDepth, the CPU's math), used in place of view.maxDistance.
  void renderToDevice(const FrameView& view, const uint64_t* slotKeys, float* deviceRgba,
                      GpuFrameTimes* times = nullptr, const DeviceDepth* depth = nullptr,
                      const float* const* slotHost = nullptr,
                      const GpuStoredSlot* stored = nullptr);
  /// The same limits brought to the host (width * height floats, row 0 = top; a frame cast on the
  /// CPU after all). Returns the number of limited pixels.
  int64_t depthLimitsToHost(const DeviceDepth& depth, std::vector<float>& limits);

  /// Benchmark helper: uploads the frame, then launches `kind` `repetitions` times (after one
  /// warm-up) and returns each launch's time.
  GpuKernelTiming timeKernel(const FrameView& view, const uint64_t* slotKeys, GpuKernelKind kind,
                             int repetitions);

  /// Fill the device image with NaN before each render so an unwritten pixel shows (tests).
  void setPoisonOutput(bool on) { poison_ = on; }
  /// Tests: every later render fails with a GpuError, as it would once the CUDA context is lost.
  void setSimulatedFailure(bool on) { simulateFailure_ = on; }
  /// Use kernels specialised on the frame's degree when all spline slots share one (default on).
  void setDegreeSpecialisation(bool on) { specialise_ = on; }
  /// Floating-point contract of the kernels used from the next call on.
  void setFloatMode(GpuFloatMode mode) { mode_ = mode; }
  GpuFloatMode floatMode() const { return mode_; }
  /// DS baseline: render raw (kSlotRaw) frames through 3D textures with hardware trilinear
  /// filtering instead of castRay's software trilinear (Full kernels only; throws
  /// InvalidArgument on spline slots).
  void setDsTextures(bool on) { dsTextures_ = on; }
  /// How the pool holds compact models from the next frame on (models resident stay as they are).
  void setPoolModels(GpuPoolModels how) { poolModels_ = how; }
  GpuPoolModels poolModels() const { return poolModels_; }
  /// Models the last frame read as codes (0: it launched the kernels reading float32 only).
  int64_t lastCompactSlots() const { return lastCompactSlots_; }
  /// Benchmark knob: 8 asks for the degree-2 kernels limited to 64 registers (8 blocks per SM).
  void setMinBlocksPerSm(int blocks) { minBlocks_ = blocks; }
  /// "full<shaded,p=2>: 40 registers, 0 bytes local" for the kernel the last frame used.
  std::string lastKernelInfo() const { return kernelInfo_; }
  /// The last render()'s times (all zero when it did not finish, e.g. a pool too small).
  const GpuFrameTimes& lastTimes() const { return lastTimes_; }

  GpuModelPool& pool();
  const GpuModelPool& pool() const;

  /// Key used for slot s when the caller gives none.
  static uint64_t defaultSlotKey(const FrameSlot& slot);
  /// Floats of a slot's model (slotFloatCount: control points or padded raw samples, and a masked
  /// model's mask words; 0 for an empty block, which takes no room in the pool).
  static uint64_t slotFloats(const FrameSlot& slot);

 private:
  /// Casts into deviceTarget (or the renderer's own device image when null), then copies the
  /// image to hostRgba when given.
  void cast(const FrameView& view, const uint64_t* slotKeys, float* deviceTarget, float* hostRgba,
            GpuFrameTimes* times, const DeviceDepth* depth, const float* const* slotHost,
            const GpuStoredSlot* stored);
  struct Impl;
  std::unique_ptr<Impl> impl_;
  bool poison_ = false;
  bool simulateFailure_ = false;
  bool specialise_ = true;
  GpuFloatMode mode_ = GpuFloatMode::Exact;
  int minBlocks_ = 1;
  GpuPoolModels poolModels_ = GpuPoolModels::Auto;
  int64_t lastCompactSlots_ = 0;
  bool dsTextures_ = false;
  std::string kernelInfo_;
  GpuFrameTimes lastTimes_;
};

}  // namespace afam
