// SPDX-License-Identifier: BSD-3-Clause
// GPU decoding of stored micro-model payloads into the float32 control points the ray caster
// reads, bit for bit what Core's decodeStoredPayload gives: constants, uncoded control points and
// coded splines in the integer Lorenzo form whose entropy frame is a lanes frame
// (entropy/lanes_coder.hpp), and interpolants whose samples are coded so or in the double
// interpolation form with a lanes frame: the samples predicted level by level as the CPU codec
// does (value_prediction.hpp), the spline through them fitted one line a thread
// (interpolation_passes.hpp, gpu_interpolants.hpp), its points rounded where the payload says
// (rounded_points.hpp). Other payloads (zstd frames, splines in the double forms, the integer
// interpolation form, masks, residual chains in time) stay with the CPU: gpuDecodable says which.
// An interpolant residual of 2^31 steps or more (never from an 8- or 16-bit scan) is refused on the
// GPU (Varint) where the CPU, which reads 64-bit residuals, would decode it.
//
// A batch of jobs is decoded from one device byte buffer (the payloads, as stored) into one device
// float buffer, by kernels on one stream: a warp per coded job undoes the lanes frame into device
// scratch (interleaved rANS, a lane per rANS state); a block per coded job parses the varints (a
// block-wide scan of the bytes that end a value), sums the Lorenzo residuals along x, y and z (in
// shared memory when the job fits, else in its output) and converts to float; a block per constant
// or uncoded job fills or copies, and one per model in a cache's compact form reads its codes
// through its table. Each job gets a status word (GpuDecodeStatus): a damaged payload
// is reported for its job, never read past its bytes, and leaves the other jobs' output as the CPU
// decodes it. On an H100: 215 GB/s of decoded floats for a 602 x 740 x 632 scan's file, about 250
// times one CPU core (bench_gpu_decode).
// Plain C++ header (no CUDA types): device pointers and the stream are void* or typed pointers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "afam/base/host_device.hpp"
#include "afam/format/afam_file.hpp"

namespace afam {

/// What a job's kernel does with its stored bytes.
enum class GpuDecodeKind : uint8_t {
  Constant = 0,        ///< 4 bytes: one float32, repeated ncp product times
  Floats = 1,          ///< the float32 control points themselves (4 * ncp product bytes)
  IntegerLorenzo = 2,  ///< coded (block_codec.hpp): integer Lorenzo form, lanes frame
  Compact = 3,  ///< a cached model's compact form (compact_form.hpp): its table, then its codes
  /// An interpolant (rounded_points.hpp): its samples coded in the integer Lorenzo form or the
  /// double interpolation form (then the point shift byte when rounded), decoded, and the spline
  /// of NCP = n through them.
  Interpolant = 4,
};

/// One payload to decode (trivially copyable: the batch is uploaded as it is).
struct GpuDecodeJob {
  uint64_t payloadOffset = 0;  ///< of the stored bytes, from the device payload buffer's start
  uint64_t storedBytes = 0;    ///< ModelEntry::storedSize
  uint64_t outputOffset = 0;   ///< of the decoded floats, in floats from the output's start
  int32_t ncp[3] = {0, 0, 0};  ///< control points per axis (x fastest in the output)
  uint32_t frameSymbols = 0;  ///< IntegerLorenzo: the frame's V as the host read it (sizes scratch)
  GpuDecodeKind kind = GpuDecodeKind::Constant;
  /// Coded: the payload's predictor byte (Predictor): IntegerLorenzo, or for an interpolant's
  /// samples also Interpolation (the double form, its frame after a 9-byte header).
  uint8_t predictor = 2;
  uint8_t codeWidth = 0;   ///< Compact: bytes a code (1 or 2)
  uint32_t codeTable = 0;  ///< Compact: floats of the table before the codes
  /// Interpolant: each axis's degree (fit.hpp's effectiveDegree of the decoder's degree).
  uint8_t degree[3] = {0, 0, 0};
  double pointStep = 0;     ///< Interpolant: its points' step q (0: not rounded)
  double pointInverse = 0;  ///< 1 / q, as roundPoints computes it
};

/// Whether a job's values are an interpolant's samples in the double interpolation form: the
/// Lorenzo kernels only parse their residuals (global memory), GpuInterpolants predicts them.
/// (kGpuInterpolationPredictor: block_codec.hpp's Predictor::Interpolation, which this header does
/// not include: its name is also the prefetch predictor's.)
constexpr uint8_t kGpuInterpolationPredictor = 1;
AFAM_HD bool gpuJobInDoubleForm(const GpuDecodeJob& j) {
  return j.kind == GpuDecodeKind::Interpolant && j.predictor == kGpuInterpolationPredictor;
}

/// The job that expands a model kept in compact form `form` (`ncp` control points per axis, the
/// form's floats at payloadOffset) into float32 points at outputOffset.
GpuDecodeJob gpuCompactJob(CompactForm form, Int3 ncp, uint64_t payloadOffset,
                           uint64_t outputOffset);

/// A job's status word after decoding: 0 when it decoded, else what is wrong with its payload.
enum class GpuDecodeStatus : uint32_t {
  Ok = 0,
  StoredSize = 1,      ///< stored bytes do not fit the kind and NCP
  CodedHeader = 2,     ///< short, invalid step, not integer Lorenzo, or invalid base
  FrameHeader = 3,     ///< lanes frame header or frequencies damaged (lanes::parseFrame)
  FrameLength = 4,     ///< V beyond 5 bytes a value, or not what the host read
  FrameState = 5,      ///< a lane's initial state below 2^16
  FrameWords = 6,      ///< words run out, or some are left, or states do not end at 2^16
  Varint = 7,          ///< a varint runs past the frame's end or is longer than 32 bits
  ValueCount = 8,      ///< not exactly one varint per control point
  Range = 9,           ///< some |k| >= 2^26
  NotFinite = 10,      ///< some value beyond float32
  NotRun = 11,         ///< the batch never ran (a CUDA failure; see the exception)
  Interpolation = 12,  ///< an interpolant's point beyond float32, or not rounding to its step
};

/// "decoded", "lanes frame is truncated or damaged", ... (for messages naming the block).
const char* gpuDecodeStatusText(uint32_t status);

/// Whether GpuBlockDecoder decodes entry e, whose stored bytes (e.storedSize of them) are at
/// `stored`: constants, uncoded splines and samples, coded integer Lorenzo payloads with a lanes
/// frame, and interpolants coded so (their point step valid); never masked models, residuals or
/// empty blocks.
bool gpuDecodable(const ModelEntry& e, const uint8_t* stored);

/// Whether entry e's payload is one gpuDecodable takes, judged from the index alone (before its
/// bytes are read): a constant, or a coded spline or interpolant in an integer form with a lanes
/// frame (both coded with Lorenzo); never masked, residual or empty. gpuDecodable still checks the
/// bytes.
bool gpuDecodesEntry(const ModelEntry& e);

/// The job of a decodable entry whose stored bytes lie at payloadOffset in the device payload
/// buffer (and at `stored` on the host) and whose floats go to outputOffset.
GpuDecodeJob gpuDecodeJob(const ModelEntry& e, const uint8_t* stored, uint64_t payloadOffset,
                          uint64_t outputOffset);

class GpuBlockDecoder {
 public:
  /// Creates the decoder's stream on `device`. Throws GpuError when CUDA fails.
  explicit GpuBlockDecoder(int device = 0);
  ~GpuBlockDecoder();
  GpuBlockDecoder(const GpuBlockDecoder&) = delete;
  GpuBlockDecoder& operator=(const GpuBlockDecoder&) = delete;

  /// Queues the decoding of `jobs` on `stream` (a cudaStream_t; nullptr: the decoder's own):
  /// reads device memory `payloads`, writes device memory `output`. Returns before the GPU is done
  /// (the job list is copied first); wait() gives the status words. Waits for the batch before
  /// when one is still in flight. Throws GpuError / GpuOutOfMemory when CUDA fails.
  void decodeAsync(const std::vector<GpuDecodeJob>& jobs, const void* payloads, float* output,
                   void* stream = nullptr);
  /// Waits for the last decodeAsync and returns its jobs' status words (GpuDecodeStatus), in the
  /// order of its jobs.
  const std::vector<uint32_t>& wait();
  /// decodeAsync, then wait.
  const std::vector<uint32_t>& decode(const std::vector<GpuDecodeJob>& jobs, const void* payloads,
                                      float* output, void* stream = nullptr);

  /// Coded jobs of at most this many control points are summed in shared memory (one pass over
  /// global memory), the others in their output; by default as many as a block's shared memory
  /// holds (55k on an H100), clamped to that. Tests set 0 to run the global path.
  void setSharedJobLimit(uint64_t controlPoints);

  void* stream() const;         ///< the decoder's own cudaStream_t
  size_t scratchBytes() const;  ///< device scratch held now (the largest batch's frames)

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace afam
