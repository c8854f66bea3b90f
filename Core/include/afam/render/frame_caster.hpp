// SPDX-License-Identifier: BSD-3-Clause
// The ray caster of a Renderer behind one interface: the CPU's (CpuCaster) and the CUDA path's
// (afam::GpuCaster in CudaKernels, made by makeGpuCaster) both take a prepared frame and that
// frame's targets, and return what they did. Caching, LOD, culling and prefetching stay the
// Renderer's; a caster only casts.
//
// A caster owns what lives across frames (threads; a GPU's model pool and stream). Where one
// frame's image and depth live is given with that frame (FrameTargets) and never kept: a frame
// that passes no device buffer gets its image on the host, whatever the frame before it did.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "afam/render/cached_model.hpp"
#include "afam/render/image.hpp"
#include "afam/scene/depth_limits.hpp"

namespace afam {

struct PreparedFrame;

/// A depth buffer already in device memory (e.g. OpenGL's, copied into a pixel buffer mapped into
/// CUDA) and how its depths become ray lengths (depthToRay in view_mapping.hpp).
struct DeviceDepth {
  const float* depth = nullptr;  ///< toRay.tileWidth * toRay.tileHeight floats, row 0 at the bottom
  DepthToRay toRay;
};

/// Where one frame's image goes and what stops its rays; for that frame only.
struct FrameTargets {
  /// Per-pixel ray length limit from opaque geometry on the host (caller-owned, width * height
  /// floats, row 0 = top; FrameView::maxDistance); nullptr: none.
  const float* maxDistance = nullptr;
  /// Device memory for the image (premultiplied RGBA, row 0 = top; e.g. an OpenGL buffer mapped
  /// into CUDA), deviceRgbaFloats floats. A frame cast on the GPU whose image fits is left there
  /// and its ImageRGBA holds the size only (rgba empty); any other frame fills the ImageRGBA.
  /// nullptr: the host. The caller keeps it valid during the frame.
  float* deviceRgba = nullptr;
  size_t deviceRgbaFloats = 0;
  /// Optional depth buffer in device memory (deviceDepth.depth null: none): the rays stop at its
  /// opaque geometry, in place of maxDistance; the limits are computed on the GPU, and brought
  /// to the host when the frame is cast on the CPU after all. A CPU caster ignores it.
  DeviceDepth deviceDepth;
};

/// What a caster did with one frame.
struct CastResult {
  bool onGpu = false;          ///< the image was cast on the GPU (false: on the CPU)
  bool imageOnDevice = false;  ///< the image is at FrameTargets::deviceRgba (ImageRGBA: size only)
  /// Pixels the device depth limited; -1 when the frame used none.
  int64_t depthLimitedPixels = -1;
  /// Models this frame copied to the GPU's pool; -1 when the caster has no working GPU.
  int64_t modelsUploaded = -1;
  /// The GPU's own times (CUDA events): model and table upload, ray casting, the image's copy to
  /// the host; -1 when the frame was not cast on the GPU.
  double gpuUploadMs = -1, gpuKernelMs = -1, gpuDownloadMs = -1;
  /// What went otherwise than asked, one sentence each, each said once per caster, e.g.
  /// "GPU model pool too small ...; this frame on the CPU".
  std::vector<std::string> messages;
  /// Models the caster decoded itself and found damaged (a GPU's decoder: their payloads passed
  /// their checksums but do not decode): the frame's entry and why. This frame drew nothing
  /// there; the renderer records them as damaged, so later frames draw what stands in for them.
  std::vector<std::pair<int64_t, std::string>> damaged;
};

class FrameCaster {
 public:
  virtual ~FrameCaster() = default;
  /// Casts `frame` (its view's host arrays) into `image` (premultiplied RGBA of the view's size,
  /// row 0 = top) or into targets.deviceRgba, limited by targets.maxDistance or
  /// targets.deviceDepth. A GPU that is full or fails does not throw: the frame is cast on the
  /// CPU and the result says so.
  virtual CastResult cast(const PreparedFrame& frame, const FrameTargets& targets,
                          ImageRGBA& image) = 0;
  /// True while frames are cast on the GPU (false for the CPU's caster and for a GPU that failed).
  virtual bool castsOnGpu() const = 0;
  /// The cudaStream_t the caster casts on (nullptr: none): where buffers shared with another API
  /// are mapped, so that their uses are ordered without host waits.
  virtual void* deviceStream() const { return nullptr; }
  /// In words: "CPU" or "NVIDIA H200 (sm_90, ...)".
  virtual std::string description() const = 0;
  /// False when the caster reads each slot's floats from PreparedFrame::slotHost (the cached
  /// models), so that the renderer leaves the frame's pool empty: no per-frame copy of the models.
  virtual bool readsHostPool() const { return true; }
  /// Entries whose models the caster decodes itself from their stored payloads (a GPU's decoder):
  /// the cache keeps those in the stored form (cache.hpp). Null: the cache decodes every model.
  virtual StoredForm storedForm() const { return nullptr; }
  /// Whether the caster reads models in the compact form (FrameSlot::codeWidth); a caster that
  /// does not leaves the cache keeping float32 models. The CPU caster reads the codes; the GPU
  /// caster's pool expands a compact model once, when it uploads it.
  virtual bool readsCompactForm() const { return true; }
};

/// The CPU ray caster (renderCpu) on `threads` threads (0: all cores); ignores device targets.
class CpuCaster : public FrameCaster {
 public:
  explicit CpuCaster(int threads) : threads_(threads) {}
  CastResult cast(const PreparedFrame& frame, const FrameTargets& targets,
                  ImageRGBA& image) override;
  bool castsOnGpu() const override { return false; }
  std::string description() const override { return "CPU"; }
  /// The rays read the cached models themselves (PreparedFrame::hostView).
  bool readsHostPool() const override { return false; }

 private:
  int threads_;
};

}  // namespace afam
