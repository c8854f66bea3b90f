// SPDX-License-Identifier: BSD-3-Clause
// GpuBlockDecoder (gpu_block_decoder.hpp). Compiled with -fmad=false; the one floating-point
// expression, float((double(base) + double(k)) * step), is also spelled with round-to-nearest
// intrinsics, so it rounds as Core's integerValue does on the CPU.
#include "afam/cuda/decode/gpu_block_decoder.hpp"

#include <cuda_runtime.h>

#include <algorithm>
#include <cstring>
#include <cub/block/block_scan.cuh>

#include "afam/entropy/lanes_coder.hpp"
#include "afam/format/block_codec.hpp"
#include "afam/format/rounded_points.hpp"
#include "afam/spline/fit.hpp"
#include "common/cuda_check.hpp"
#include "decode/gpu_interpolants.hpp"

namespace afam {

namespace {

using Status = GpuDecodeStatus;
constexpr uint32_t code(Status s) { return uint32_t(s); }

constexpr int kWarp = 32;
constexpr int kThreads = 256;  // a block of lorenzoGlobalKernel and simpleKernel
constexpr int kBytesPerThread = 16;
// Frame bytes lorenzoGlobalKernel parses at a time.
constexpr int kChunk = kThreads * kBytesPerThread;
constexpr uint32_t kLimit = 1u << 26;   // every |k| < 2^26 (integer_codec.cpp)
constexpr uint64_t kScratchAlign = 16;  // the parser loads 16 bytes at a time

/// A coded job's place in the batch (device side).
struct CodedJob {
  uint64_t scratchOffset = 0;  ///< of its decoded frame bytes, a multiple of kScratchAlign
  uint32_t job = 0;            ///< index in the batch's jobs
  uint32_t pad = 0;
};

uint64_t roundUp(uint64_t v, uint64_t a) { return (v + a - 1) / a * a; }

// ------------------------------------------------------------------------------------------------
// Device helpers

__device__ __forceinline__ uint64_t readU64(const uint8_t* p) {
  return uint64_t(lanes::readU32(p)) | uint64_t(lanes::readU32(p + 4)) << 32;
}

__device__ __forceinline__ uint64_t controlPoints(const GpuDecodeJob& j) {
  return uint64_t(uint32_t(j.ncp[0])) * uint32_t(j.ncp[1]) * uint32_t(j.ncp[2]);
}

/// Bytes of a coded job's samples or points: an interpolant's point shift byte follows them.
__device__ __forceinline__ uint64_t codedBytes(const GpuDecodeJob& j) {
  const bool rounded = j.kind == GpuDecodeKind::Interpolant && j.pointStep > 0 &&
                       j.storedBytes >= kRoundedPointsBytes;
  return rounded ? j.storedBytes - kRoundedPointsBytes : j.storedBytes;
}

static_assert(kGpuInterpolationPredictor == uint8_t(Predictor::Interpolation),
              "the double interpolation form's predictor byte");

/// Bytes before a coded job's frame: the double forms' header, or the integer forms'.
__device__ __forceinline__ uint64_t headerBytes(const GpuDecodeJob& j) {
  return gpuJobInDoubleForm(j) ? kCodedHeaderBytes : kIntegerCodedHeaderBytes;
}

/// The coded payload's step and base (0 in a double form), checked as decodeValues and
/// decodeInteger check them.
__device__ uint32_t readCodedHeader(const GpuDecodeJob& job, const uint8_t* p, double& step,
                                    int64_t& base) {
  const uint64_t bytes = codedBytes(job);
  if (bytes < headerBytes(job) + 1) return code(Status::CodedHeader);
  step = __longlong_as_double((long long)readU64(p));
  if (!(step > 0) || isinf(step)) return code(Status::CodedHeader);
  base = 0;
  if (gpuJobInDoubleForm(job)) return code(Status::Ok);  // the host checked its predictor byte
  if (p[8] != uint8_t(Predictor::IntegerLorenzo)) return code(Status::CodedHeader);
  base = int64_t(readU64(p + 9));
  const int64_t limit = int64_t(1) << 52;
  if (!(base > -limit && base < limit)) return code(Status::CodedHeader);
  return code(Status::Ok);
}

/// Core's integerValue: float((double(base) + double(k)) * step), each operation rounded to
/// nearest, none fused.
__device__ __forceinline__ float integerValue(int64_t base, uint32_t k, double step) {
  return __double2float_rn(
      __dmul_rn(__dadd_rn(__ll2double_rn((long long)base), __int2double_rn(int32_t(k))), step));
}

/// Word w of a frame's word stream, 0 past its end.
__device__ __forceinline__ uint32_t wordAt(const uint8_t* words, uint32_t count, uint32_t w) {
  return w < count ? lanes::readU16(words + 2 * size_t(w)) : 0u;
}

// ------------------------------------------------------------------------------------------------
// Kernel A: a warp undoes one lanes frame (lanes_coder.hpp) into the job's scratch bytes.

struct FrameShared {
  uint32_t table[lanes::kScale];
  uint32_t frequency[256];
  uint32_t cumulative[256];
  uint16_t ring[1024];  // WordRing::kRing
  uint32_t status, symbols, lanes, words, largest;
  uint64_t statesAt, wordsAt;
};

/// Lane 0: the payload's header and the frame's (lanes::parseFrame), checked as the CPU checks
/// them, into s.
__device__ void parseCodedFrame(const GpuDecodeJob& job, const uint8_t* stored, FrameShared& s) {
  double step;
  int64_t base;
  s.status = readCodedHeader(job, stored, step, base);
  if (s.status) return;
  const uint64_t count = controlPoints(job);
  const uint8_t* frame = stored + headerBytes(job);
  const lanes::FrameLayout f =
      lanes::parseFrame(frame, codedBytes(job) - headerBytes(job), s.frequency);
  if (f.error) {
    s.status = code(Status::FrameHeader);
    return;
  }
  // The CPU decodes at most 5 bytes a value (unpackFrame's capacity); the host sized the
  // scratch by the V it read.
  if (f.symbols > 5 * count || f.symbols != job.frameSymbols || count > 0xffffffffu) {
    s.status = code(Status::FrameLength);
    return;
  }
  uint32_t sum = 0, largest = 0;
  for (int b = 0; b < 256; ++b) {
    s.cumulative[b] = sum;
    sum += s.frequency[b];
    if (s.frequency[b]) largest = uint32_t(b);
  }
  s.symbols = f.symbols;
  s.lanes = uint32_t(f.lanes);
  s.words = f.words;
  s.largest = largest;
  s.statesAt = f.statesAt;
  s.wordsAt = f.wordsAt;
}

/// lanes::buildTable's entries, a lane per slot of each byte's range.
__device__ void fillTable(FrameShared& s, int lane) {
  for (uint32_t b = 0; b <= s.largest; ++b) {
    const uint32_t f = s.frequency[b], c = s.cumulative[b];
    for (uint32_t k = uint32_t(lane); k < f; k += kWarp) s.table[c + k] = lanes::packSlot(b, f, k);
  }
}

/// The frame's words pass through a ring in shared memory: it holds words [lo, lo + kRing) and a
/// step reads at most 32 from pos < lo + kRefill. Each lane keeps the next kRefill words' share in
/// registers, loaded one refill ahead, so a refill stores them without waiting for memory.
class WordRing {
 public:
  __device__ WordRing(const uint8_t* words, uint32_t count, uint16_t* ring, int lane)
      : words_(words), count_(count), ring_(ring), lane_(uint32_t(lane)) {
    fetch(0);
    store(0);
    fetch(kRefill);
    store(kRefill);
    fetch(kRing);
    __syncwarp();
  }
  __device__ uint32_t operator[](uint32_t w) const { return ring_[w & (kRing - 1)]; }
  /// After a step: when pos has left the ring's first half, its slots take the next words.
  __device__ void advance(uint32_t pos) {
    if (pos < lo_ + kRefill) return;  // the same in every lane
    __syncwarp();                     // every lane has read the slots about to be overwritten
    store(lo_ + kRing);
    fetch(lo_ + kRing + kRefill);
    lo_ += kRefill;
    __syncwarp();
  }

  static constexpr uint32_t kRing = 1024, kRefill = kRing / 2, kPerLane = kRefill / kWarp;

 private:
  __device__ void fetch(uint32_t from) {
#pragma unroll
    for (uint32_t t = 0; t < kPerLane; ++t)
      next_[t] = wordAt(words_, count_, from + lane_ + kWarp * t);
  }
  __device__ void store(uint32_t from) {
#pragma unroll
    for (uint32_t t = 0; t < kPerLane; ++t)
      ring_[(from + lane_ + kWarp * t) & (kRing - 1)] = uint16_t(next_[t]);
  }
  const uint8_t* words_;
  uint32_t count_;
  uint16_t* ring_;
  uint32_t lane_, lo_ = 0;
  uint32_t next_[kPerLane];
};

static_assert(sizeof(FrameShared::ring) / sizeof(uint16_t) == WordRing::kRing, "ring size");

/// The rANS steps: at step t lane l decodes byte t * L + l; the lanes that renormalise take the
/// next words in lane order (a ballot's rank). Returns whether the frame ends as a valid one does.
__device__ bool runLanes(const uint8_t* frame, FrameShared& s, uint8_t* out, int lane) {
  const uint32_t L = s.lanes, V = s.symbols, count = s.words;
  const bool mine = uint32_t(lane) < L;
  uint32_t x = mine ? lanes::readU32(frame + s.statesAt + 4 * size_t(lane)) : lanes::kLow;
  WordRing ring(frame + s.wordsAt, count, s.ring, lane);
  const uint32_t below = (1u << lane) - 1u;
  uint32_t pos = 0;
  bool over = false;
  for (uint64_t first = 0; first < V; first += L) {
    const uint64_t i = first + uint32_t(lane);
    bool need = false;
    if (mine && i < V) {
      out[i] = uint8_t(lanes::decodeStep(x, s.table));
      need = x < lanes::kLow;
    }
    const uint32_t ballot = __ballot_sync(0xffffffffu, need);
    if (need) {
      const uint32_t w = pos + __popc(ballot & below);
      over = over || w >= count;
      x = (x << 16) | ring[w];
    }
    pos += __popc(ballot);
    ring.advance(pos);
  }
  return __all_sync(0xffffffffu, !over && pos == count && x == lanes::kLow);
}

__global__ void __launch_bounds__(kWarp)
    decodeFramesKernel(const GpuDecodeJob* __restrict__ jobs, const CodedJob* __restrict__ coded,
                       const uint8_t* __restrict__ payloads, uint8_t* __restrict__ scratch,
                       uint32_t* __restrict__ status) {
  __shared__ FrameShared s;
  const int lane = int(threadIdx.x);
  const CodedJob c = coded[blockIdx.x];
  const GpuDecodeJob job = jobs[c.job];
  const uint8_t* stored = payloads + job.payloadOffset;
  if (lane == 0) parseCodedFrame(job, stored, s);
  __syncwarp();
  if (s.status) {
    if (lane == 0) status[c.job] = s.status;
    return;
  }
  const uint8_t* frame = stored + headerBytes(job);
  const bool low = uint32_t(lane) < s.lanes &&
                   lanes::readU32(frame + s.statesAt + 4 * size_t(lane)) < lanes::kLow;
  if (__any_sync(0xffffffffu, low)) {
    if (lane == 0) status[c.job] = code(Status::FrameState);
    return;
  }
  fillTable(s, lane);
  __syncwarp();
  if (!runLanes(frame, s, scratch + c.scratchOffset, lane) && lane == 0)
    status[c.job] = code(Status::FrameWords);
}

// ------------------------------------------------------------------------------------------------
// Kernel B: a block turns one job's frame bytes into residuals, k and floats. Jobs whose control
// points fit in shared memory are summed there (lorenzoSharedKernel, one pass over global memory);
// larger ones in the job's output (lorenzoGlobalKernel).

/// The varint that ends at byte p (a byte < 0x80) of v, read backwards over the bytes >= 0x80
/// before it; false where the CPU's reader refuses it (more than 5 bytes, or 5 whose last holds
/// bits beyond 32).
__device__ bool varintEndingAt(const uint8_t* v, uint64_t p, uint32_t& u) {
  const uint32_t last = v[p];
  uint32_t value = last;
  int length = 1;
  while (uint64_t(length) <= p) {
    const uint32_t b = v[p - uint64_t(length)];
    if (b < 0x80u) break;
    if (length == 5) return false;
    value = (value << 7) | (b & 0x7fu);
    ++length;
  }
  if (length == 5 && last > 0x0fu) return false;
  u = value;
  return true;
}

__device__ __forceinline__ uint32_t unzigzag(uint32_t u) { return (u >> 1) ^ (0u - (u & 1u)); }

__device__ __forceinline__ uint32_t byteOf(const uint32_t (&word)[4], int j) {
  return (word[j >> 2] >> (8 * (j & 3))) & 0xffu;
}

/// This thread's 16 bytes of a chunk (those at and past V read as 0x80, which ends nothing), and
/// the mask of those that end a value.
__device__ __forceinline__ uint32_t loadBytes(const uint8_t* v, uint64_t at, uint64_t V,
                                              uint32_t (&word)[4]) {
  if (at < V) {
    const uint4 q = *reinterpret_cast<const uint4*>(v + at);
    word[0] = q.x, word[1] = q.y, word[2] = q.z, word[3] = q.w;
  } else {
    word[0] = word[1] = word[2] = word[3] = 0x80808080u;
  }
  uint32_t ends = 0;
#pragma unroll
  for (int j = 0; j < kBytesPerThread; ++j)
    if (byteOf(word, j) < 0x80u && at + uint64_t(j) < V) ends |= 1u << j;
  return ends;
}

/// Parses the V varints at v (16-byte aligned) with a block of T threads, handing each residual
/// to sink.put(index, value) and each chunk's end to sink.flush(chunk's first index, values);
/// returns the block's status (the same in every thread).
template <int T, typename Sink>
__device__ uint32_t parseResiduals(const uint8_t* v, uint64_t V, uint32_t count,
                                   typename cub::BlockScan<uint32_t, T>::TempStorage& scan,
                                   Sink& sink) {
  uint32_t done = 0;
  int bad = V > 0 && v[V - 1] >= 0x80u;  // the last value ends past the frame
  for (uint64_t chunk = 0; chunk < V; chunk += uint64_t(T) * kBytesPerThread) {
    const uint64_t at = chunk + uint64_t(threadIdx.x) * kBytesPerThread;
    uint32_t word[4];
    const uint32_t ends = loadBytes(v, at, V, word);
    uint32_t first, total;
    cub::BlockScan<uint32_t, T>(scan).ExclusiveSum(uint32_t(__popc(ends)), first, total);
#pragma unroll
    for (int j = 0; j < kBytesPerThread; ++j) {
      if (!((ends >> j) & 1u)) continue;
      const uint32_t before = j > 0 ? byteOf(word, j - 1) : (at > 0 ? v[at - 1] : 0u);
      uint32_t u = byteOf(word, j);  // one byte: |residual| < 64, the common case
      if (before >= 0x80u && !varintEndingAt(v, at + uint64_t(j), u)) bad = 1;
      sink.put(first++, done, unzigzag(u));
    }
    __syncthreads();
    sink.flush(done, total);
    done += total;
    __syncthreads();  // the scan's storage is reused by the next chunk
  }
  if (__syncthreads_or(bad)) return code(Status::Varint);
  return done == count ? code(Status::Ok) : code(Status::ValueCount);
}

/// Residuals into shared memory at their index (k: count of them).
struct SharedSink {
  uint32_t* k;
  uint32_t count;
  __device__ void put(uint32_t inChunk, uint32_t done, uint32_t value) {
    if (done + inChunk < count) k[done + inChunk] = value;
  }
  __device__ void flush(uint32_t, uint32_t) {}
};

/// Residuals staged a chunk at a time in shared memory, written out to global memory coalesced.
struct GlobalSink {
  uint32_t* staged;  // kChunk of them
  uint32_t* r;
  uint32_t count;
  __device__ void put(uint32_t inChunk, uint32_t, uint32_t value) { staged[inChunk] = value; }
  __device__ void flush(uint32_t done, uint32_t total) {
    for (uint32_t t = threadIdx.x; t < total; t += blockDim.x)
      if (done + t < count) r[done + t] = staged[t];
  }
};

/// Inclusive prefix sums along x of the rows of k (rows of nx, x fastest): each warp takes a
/// run of whole rows and scans them 32 consecutive values at a time (coalesced, and free of
/// shared-memory bank conflicts), each value summing only over its own row.
__device__ void sumRows(uint32_t* k, uint32_t nx, uint32_t rows) {
  const uint32_t lane = threadIdx.x % kWarp, warp = threadIdx.x / kWarp;
  const uint32_t warps = blockDim.x / kWarp, share = (rows + warps - 1) / warps;
  const uint32_t first = min(rows, warp * share), last = min(rows, first + share);
  const uint32_t end = last * nx;
  uint32_t carry = 0;  // the sum so far of the row the tile starts in
  for (uint32_t base = first * nx; base < end; base += kWarp) {
    const uint32_t i = base + lane;
    uint32_t v = i < end ? k[i] : 0u;
    const int head = int(lane) - int(i % nx);  // lane of its row's first value (< 0: before)
#pragma unroll
    for (int d = 1; d < kWarp; d *= 2) {
      const uint32_t u = __shfl_up_sync(0xffffffffu, v, d);
      if (int(lane) - d >= max(head, 0)) v += u;
    }
    if (head < 0) v += carry;
    if (i < end) k[i] = v;
    carry = __shfl_sync(0xffffffffu, v, kWarp - 1);
  }
}

/// Inverse Lorenzo (integer_codec.cpp's lorenzoSums): inclusive prefix sums of k along x, y and z
/// in wrapping uint32 arithmetic (in any order the same sums), then each k to its float's bits in
/// out (which may be k itself: one type, so no access is reordered) with the CPU's checks.
/// Returns the block's status.
__device__ uint32_t lorenzoToFloats(uint32_t* k, uint32_t* out, const int32_t (&ncp)[3],
                                    int64_t base, double step) {
  const uint32_t nx = uint32_t(ncp[0]), ny = uint32_t(ncp[1]), nz = uint32_t(ncp[2]);
  const uint32_t plane = nx * ny;
  sumRows(k, nx, ny * nz);
  __syncthreads();
  for (uint32_t column = threadIdx.x; column < nx * nz; column += blockDim.x) {  // along y
    const uint32_t z = column / nx, x = column - z * nx;
    uint32_t* p = k + size_t(z) * plane + x;
    uint32_t sum = p[0];
    for (uint32_t y = 1; y < ny; ++y) p[size_t(y) * nx] = sum += p[size_t(y) * nx];
  }
  __syncthreads();
  int outside = 0, infinite = 0;
  for (uint32_t i = threadIdx.x; i < plane; i += blockDim.x) {  // along z, then to float
    uint32_t sum = 0;
    for (uint32_t z = 0; z < nz; ++z) {
      const size_t at = size_t(z) * plane + i;
      sum += k[at];
      outside |= sum + (kLimit - 1) > 2 * (kLimit - 1);
      const float value = integerValue(base, sum, step);
      infinite |= !isfinite(value);
      out[at] = __float_as_uint(value);
    }
  }
  if (__syncthreads_or(outside)) return code(Status::Range);
  return __syncthreads_or(infinite) ? code(Status::NotFinite) : code(Status::Ok);
}

/// After the parse: k (a job's residuals) summed and converted into its output. The job's fields
/// are read again here rather than kept through the parse (fewer registers). Its header was
/// checked by decodeFramesKernel.
__device__ uint32_t finishJob(const GpuDecodeJob& job, const uint8_t* payloads, uint32_t* k,
                              float* output) {
  double step = 0;
  int64_t base = 0;
  (void)readCodedHeader(job, payloads + job.payloadOffset, step, base);
  uint32_t* out = reinterpret_cast<uint32_t*>(output + job.outputOffset);
  return lorenzoToFloats(k ? k : out, out, job.ncp, base, step);
}

constexpr int kSharedThreads = 1024;

__global__ void __launch_bounds__(kSharedThreads)
    lorenzoSharedKernel(const GpuDecodeJob* __restrict__ jobs, const CodedJob* __restrict__ coded,
                        const uint8_t* __restrict__ payloads, const uint8_t* __restrict__ scratch,
                        float* __restrict__ output, uint32_t* __restrict__ status) {
  __shared__ typename cub::BlockScan<uint32_t, kSharedThreads>::TempStorage scan;
  extern __shared__ uint4 dynamicShared[];
  const CodedJob c = coded[blockIdx.x];
  if (status[c.job]) return;  // the frame did not decode (the same word for the whole block)
  const GpuDecodeJob& job = jobs[c.job];
  uint32_t* k = reinterpret_cast<uint32_t*>(dynamicShared);
  const uint32_t count = uint32_t(controlPoints(job));  // < 2^32: decodeFramesKernel checked it
  SharedSink sink{k, count};
  uint32_t result = parseResiduals<kSharedThreads>(scratch + c.scratchOffset, job.frameSymbols,
                                                   count, scan, sink);
  if (result == 0) {
    __syncthreads();
    result = finishJob(job, payloads, k, output);
  }
  if (result && threadIdx.x == 0) status[c.job] = result;
}

__global__ void __launch_bounds__(kThreads)
    lorenzoGlobalKernel(const GpuDecodeJob* __restrict__ jobs, const CodedJob* __restrict__ coded,
                        const uint8_t* __restrict__ payloads, const uint8_t* __restrict__ scratch,
                        float* __restrict__ output, uint32_t* __restrict__ status) {
  __shared__ typename cub::BlockScan<uint32_t, kThreads>::TempStorage scan;
  __shared__ uint32_t staged[kChunk];
  const CodedJob c = coded[blockIdx.x];
  if (status[c.job]) return;
  const GpuDecodeJob& job = jobs[c.job];
  const uint32_t count = uint32_t(controlPoints(job));
  GlobalSink sink{staged, reinterpret_cast<uint32_t*>(output + job.outputOffset), count};
  uint32_t result =
      parseResiduals<kThreads>(scratch + c.scratchOffset, job.frameSymbols, count, scan, sink);
  if (result == 0 &&
      !gpuJobInDoubleForm(job)) {  // a double form's residuals stay for its prediction
    __syncthreads();  // the residuals written by every thread are visible to every thread
    result = finishJob(job, payloads, nullptr, output);
  }
  if (result && threadIdx.x == 0) status[c.job] = result;
}

// ------------------------------------------------------------------------------------------------
// Kernel C: a block per constant, uncoded or compact job.

/// A compact job's points: each code read through the table (compact_form.hpp's expandCompact,
/// the same floats); a size that does not fit the form, or a code past the table, is its status.
__device__ void expandCompactJob(const GpuDecodeJob& job, const uint8_t* stored, uint64_t count,
                                 uint32_t* out, uint32_t& status) {
  const uint64_t width = job.codeWidth;
  const bool fits = (width == 1 || width == 2) && job.payloadOffset % 4 == 0 &&
                    job.storedBytes == 4 * compactFloats(job.codeTable, width, count);
  if (!fits) {
    if (threadIdx.x == 0) status = code(Status::StoredSize);
    return;
  }
  const uint32_t* table = reinterpret_cast<const uint32_t*>(stored);
  const uint8_t* codes = stored + 4 * uint64_t(job.codeTable);
  bool past = false;
  for (uint64_t i = threadIdx.x; i < count; i += kThreads) {
    uint32_t c = codes[i * width];
    if (width == 2) c |= uint32_t(codes[i * 2 + 1]) << 8;  // little-endian, as written
    past |= c >= job.codeTable;
    out[i] = past ? 0u : table[c];
  }
  if (past) status = code(Status::Range);
}

__global__ void __launch_bounds__(kThreads)
    simpleKernel(const GpuDecodeJob* __restrict__ jobs, const uint32_t* __restrict__ simple,
                 const uint8_t* __restrict__ payloads, float* __restrict__ output,
                 uint32_t* __restrict__ status) {
  const uint32_t index = simple[blockIdx.x];
  const GpuDecodeJob job = jobs[index];
  const uint8_t* stored = payloads + job.payloadOffset;
  const uint64_t count = controlPoints(job);
  uint32_t* out = reinterpret_cast<uint32_t*>(output + job.outputOffset);
  if (job.kind == GpuDecodeKind::Constant) {
    if (job.storedBytes < 4) {
      if (threadIdx.x == 0) status[index] = code(Status::StoredSize);
      return;
    }
    const uint32_t c = lanes::readU32(stored);
    for (uint64_t i = threadIdx.x; i < count; i += kThreads) out[i] = c;
    return;
  }
  if (job.kind == GpuDecodeKind::Compact) {
    expandCompactJob(job, stored, count, out, status[index]);
    return;
  }
  if (job.kind != GpuDecodeKind::Floats || job.storedBytes != 4 * count) {
    if (threadIdx.x == 0) status[index] = code(Status::StoredSize);
    return;
  }
  if (job.payloadOffset % 4 == 0) {  // payloads are 4-aligned in a file: the common case
    const uint32_t* in = reinterpret_cast<const uint32_t*>(stored);
    for (uint64_t i = threadIdx.x; i < count; i += kThreads) out[i] = in[i];
  } else {
    for (uint64_t i = threadIdx.x; i < count; i += kThreads)
      out[i] = lanes::readU32(stored + 4 * i);
  }
}

}  // namespace

// ------------------------------------------------------------------------------------------------
// Host side

const char* gpuDecodeStatusText(uint32_t status) {
  switch (Status(status)) {
    case Status::Ok:
      return "decoded";
    case Status::StoredSize:
      return "stored payload's size does not fit its kind and control points";
    case Status::CodedHeader:
      return "coded payload's header is damaged (length, step, predictor or base)";
    case Status::FrameHeader:
      return "lanes frame's header or frequencies are damaged";
    case Status::FrameLength:
      return "lanes frame decodes to more bytes than its block holds";
    case Status::FrameState:
      return "lanes frame has an invalid state";
    case Status::FrameWords:
      return "lanes frame is truncated or damaged (its states do not end where the encoder began)";
    case Status::Varint:
      return "coded payload's residuals are damaged (a varint runs past the end or past 32 bits)";
    case Status::ValueCount:
      return "coded payload holds a wrong number of residuals";
    case Status::Range:
      return "coded payload decodes beyond its range";
    case Status::NotFinite:
      return "coded payload decodes to a value beyond float32";
    case Status::NotRun:
      return "was not decoded (the GPU batch failed)";
    case Status::Interpolation:
      return "interpolant's points overflow float32 or do not round to its point step";
  }
  return "unknown GPU decoding status";
}

namespace {

/// The decoder's degree of an interpolant (decodeInterpolant's): the largest of its axes', 1 at
/// least.
int interpolantDegree(const ModelEntry& e) {
  return std::max({int(e.degree[0]), int(e.degree[1]), int(e.degree[2]), 1});
}

/// Bytes of e's coded samples or points (an interpolant's point shift byte after them).
size_t codedBytesOf(const ModelEntry& e) {
  return e.kind == BlockKind::Interpolant && e.roundedPoints && e.storedSize >= kRoundedPointsBytes
             ? e.storedSize - kRoundedPointsBytes
             : e.storedSize;
}

/// An interpolant's point step, where the payload's is valid (else the CPU refuses it): false
/// when it is not.
bool validPointStep(const ModelEntry& e, const uint8_t* stored, double& q) {
  q = 0;
  if (!e.roundedPoints) return true;
  try {
    q = roundedPointStep(stored, e.storedSize, "gpu");
    return true;
  } catch (const FormatError&) {
    return false;
  }
}

/// Where a coded payload's lanes frame starts, for the forms the GPU decodes (0: another form):
/// after the integer header of IntegerLorenzo, or after the double header of an interpolant's
/// samples in the interpolation form.
size_t frameAt(const ModelEntry& e, const uint8_t* stored) {
  if (codedBytesOf(e) < kIntegerCodedHeaderBytes) return 0;
  const auto predictor = Predictor(stored[8]);
  if (e.integerCoded && predictor == Predictor::IntegerLorenzo) return kIntegerCodedHeaderBytes;
  if (e.kind == BlockKind::Interpolant && !e.integerCoded && predictor == Predictor::Interpolation)
    return kCodedHeaderBytes;
  return 0;
}

}  // namespace

bool gpuDecodable(const ModelEntry& e, const uint8_t* stored) {
  if (e.masked || e.residual || e.kind == BlockKind::Empty) return false;
  const int64_t count = controlCount(e);
  if (count <= 0 || e.size != uint64_t(count) * 4) return false;
  if (e.kind == BlockKind::Constant) return e.storedSize >= 4;
  if (!e.coded) return e.kind != BlockKind::Interpolant && e.storedSize == e.size;
  if (e.kind == BlockKind::Interpolant) {
    double q;
    if (interpolantDegree(e) > kMaxDegree || !validPointStep(e, stored, q)) return false;
  }
  // Coded: the integer Lorenzo form in a lanes frame (an interpolant's samples also the double
  // interpolation form), its flags as the payload says (else the CPU refuses it, and says why).
  const size_t coded = codedBytesOf(e), head = frameAt(e, stored);
  return e.lanesCoded && head > 0 && coded > head &&
         lanes::isLanesFrame(stored + head, coded - head) && count <= 0xffffffffll;
}

bool gpuDecodesEntry(const ModelEntry& e) {
  if (e.masked || e.residual) return false;
  return e.kind == BlockKind::Constant ||
         (e.kind == BlockKind::Spline && e.coded && e.integerCoded && e.lanesCoded) ||
         (e.kind == BlockKind::Interpolant && e.coded && !e.integerCoded && e.lanesCoded);
}

GpuDecodeJob gpuDecodeJob(const ModelEntry& e, const uint8_t* stored, uint64_t payloadOffset,
                          uint64_t outputOffset) {
  GpuDecodeJob j;
  j.payloadOffset = payloadOffset;
  j.storedBytes = e.storedSize;
  j.outputOffset = outputOffset;
  for (int a = 0; a < 3; ++a) j.ncp[a] = e.ncp[a];
  j.kind = e.kind == BlockKind::Constant      ? GpuDecodeKind::Constant
           : e.kind == BlockKind::Interpolant ? GpuDecodeKind::Interpolant
           : e.coded                          ? GpuDecodeKind::IntegerLorenzo
                                              : GpuDecodeKind::Floats;
  const size_t coded = codedBytesOf(e), head = e.coded ? frameAt(e, stored) : 0;
  if (j.kind != GpuDecodeKind::Constant && head > 0 && coded > head) {
    j.frameSymbols = lanes::frameSymbols(stored + head, coded - head);
    j.predictor = stored[8];
  }
  if (j.kind == GpuDecodeKind::Interpolant) {
    for (int a = 0; a < 3; ++a)
      j.degree[a] = uint8_t(effectiveDegree(interpolantDegree(e), e.ncp[a]));
    double q = 0;
    if (validPointStep(e, stored, q) && q > 0) {
      j.pointStep = q;
      j.pointInverse = 1.0 / q;
    }
  }
  return j;
}

namespace {

/// How a batch's jobs go to the kernels: the coded ones (those summed in shared memory first),
/// each with its scratch, and the constant and uncoded ones.
struct BatchLayout {
  std::vector<CodedJob> coded;
  size_t sharedJobs = 0;      ///< coded[0, sharedJobs) go to lorenzoSharedKernel
  uint64_t sharedPoints = 0;  ///< the most control points of those
  std::vector<uint32_t> simple;
  uint64_t scratchBytes = 0;
};

uint64_t jobPoints(const GpuDecodeJob& j) {
  return uint64_t(uint32_t(j.ncp[0])) * uint32_t(j.ncp[1]) * uint32_t(j.ncp[2]);
}

}  // namespace

GpuDecodeJob gpuCompactJob(CompactForm form, Int3 ncp, uint64_t payloadOffset,
                           uint64_t outputOffset) {
  GpuDecodeJob j;
  j.kind = GpuDecodeKind::Compact;
  j.ncp[0] = ncp[0];
  j.ncp[1] = ncp[1];
  j.ncp[2] = ncp[2];
  j.codeWidth = uint8_t(form.width);
  j.codeTable = form.table;
  j.payloadOffset = payloadOffset;
  j.outputOffset = outputOffset;
  j.storedBytes = 4 * compactFloats(form.table, uint64_t(form.width), jobPoints(j));
  return j;
}

namespace {

BatchLayout layOut(const std::vector<GpuDecodeJob>& jobs, uint64_t sharedLimit) {
  BatchLayout b;
  std::vector<CodedJob> large;
  for (size_t i = 0; i < jobs.size(); ++i) {
    const GpuDecodeJob& j = jobs[i];
    if (j.kind != GpuDecodeKind::IntegerLorenzo && j.kind != GpuDecodeKind::Interpolant) {
      b.simple.push_back(uint32_t(i));
      continue;
    }
    // Scratch for the frame's bytes: at most 5 a value (the kernel refuses more).
    const uint64_t points = jobPoints(j);
    CodedJob c;
    c.scratchOffset = b.scratchBytes;
    c.job = uint32_t(i);
    b.scratchBytes += roundUp(std::min<uint64_t>(j.frameSymbols, 5 * points), kScratchAlign);
    if (points <= sharedLimit && !gpuJobInDoubleForm(j)) {
      b.coded.push_back(c);
      b.sharedPoints = std::max(b.sharedPoints, points);
    } else {
      large.push_back(c);
    }
  }
  b.sharedJobs = b.coded.size();
  b.coded.insert(b.coded.end(), large.begin(), large.end());
  return b;
}

}  // namespace

struct GpuBlockDecoder::Impl {
  int device = 0;
  cudaStream_t own = nullptr;
  cudaEvent_t done = nullptr;
  bool inFlight = false;
  uint64_t sharedCapacity = 0;  ///< control points lorenzoSharedKernel can hold
  uint64_t sharedLimit = 0;     ///< jobs of at most this many go to it
  // Device: the batch's tables (jobs, coded jobs, simple job indices) in one buffer, so that
  // one copy uploads them; the status words; the frames' decoded bytes.
  void* tables = nullptr;
  size_t tablesCapacity = 0;
  uint32_t* status = nullptr;
  size_t statusCapacity = 0;
  uint8_t* scratch = nullptr;
  size_t scratchCapacity = 0;
  // Pinned host mirrors of the tables and the status words.
  unsigned char* staging = nullptr;
  size_t stagingCapacity = 0;
  uint32_t* statusHost = nullptr;
  size_t statusHostCapacity = 0;
  std::vector<uint32_t> result;
  size_t jobCount = 0;
  GpuInterpolants interpolants;  // the batch's interpolant jobs, fitted after their samples
  bool hasInterpolants = false;

  void release() noexcept {
    if (own) (void)cudaStreamSynchronize(own);
    if (done) (void)cudaEventSynchronize(done);
    if (done) (void)cudaEventDestroy(done);
    if (own) (void)cudaStreamDestroy(own);
    for (void* p : {tables, static_cast<void*>(status), static_cast<void*>(scratch)})
      if (p) (void)cudaFree(p);
    for (void* p : {static_cast<void*>(staging), static_cast<void*>(statusHost)})
      if (p) (void)cudaFreeHost(p);
    interpolants.release();
    (void)cudaGetLastError();
  }

  /// The shared memory a block of lorenzoSharedKernel may take beyond its own, all of it allowed.
  void allowSharedMemory() {
    int optIn = 0;
    AFAM_CUDA_CHECK(
        cudaDeviceGetAttribute(&optIn, cudaDevAttrMaxSharedMemoryPerBlockOptin, device));
    cudaFuncAttributes attributes{};
    AFAM_CUDA_CHECK(cudaFuncGetAttributes(&attributes, lorenzoSharedKernel));
    const size_t bytes = size_t(optIn) - attributes.sharedSizeBytes;
    AFAM_CUDA_CHECK(cudaFuncSetAttribute(lorenzoSharedKernel,
                                         cudaFuncAttributeMaxDynamicSharedMemorySize, int(bytes)));
    sharedCapacity = sharedLimit = bytes / sizeof(uint32_t);
  }

  /// Buffer *p (device memory, or pinned host memory) holds at least `bytes`; a device buffer
  /// grows by half again at least. The batch before has finished, so nothing in flight reads it.
  template <typename T>
  static void reserve(T*& p, size_t& capacity, size_t bytes, bool pinnedHost) {
    if (bytes <= capacity) return;
    const size_t want = pinnedHost ? bytes : std::max(bytes, capacity + capacity / 2);
    if (p) AFAM_CUDA_CHECK(pinnedHost ? cudaFreeHost(p) : cudaFree(p));
    p = nullptr;
    capacity = 0;
    void* raw = nullptr;
    AFAM_CUDA_CHECK(pinnedHost ? cudaMallocHost(&raw, want) : cudaMalloc(&raw, want));
    p = static_cast<T*>(raw);
    capacity = want;
  }
  template <typename T>
  static void reserveDevice(T*& p, size_t& capacity, size_t bytes) {
    reserve(p, capacity, bytes, false);
  }
  template <typename T>
  static void reserveHost(T*& p, size_t& capacity, size_t bytes) {
    reserve(p, capacity, bytes, true);
  }

  /// Device tables of a batch, after upload().
  struct Tables {
    const GpuDecodeJob* jobs;
    const CodedJob* coded;
    const uint32_t* simple;
  };

  /// Copies the jobs and the layout's lists to the device on `stream` (through pinned staging),
  /// after growing every buffer the batch needs.
  Tables upload(const std::vector<GpuDecodeJob>& jobs, const BatchLayout& b, cudaStream_t stream) {
    const size_t n = jobs.size();
    const size_t jobBytes = roundUp(n * sizeof(GpuDecodeJob), 16);
    const size_t codedBytes = roundUp(b.coded.size() * sizeof(CodedJob), 16);
    const size_t tableBytes = jobBytes + codedBytes + b.simple.size() * sizeof(uint32_t);
    reserveHost(staging, stagingCapacity, tableBytes);
    reserveHost(statusHost, statusHostCapacity, n * sizeof(uint32_t));
    reserveDevice(tables, tablesCapacity, tableBytes);
    reserveDevice(status, statusCapacity, n * sizeof(uint32_t));
    reserveDevice(scratch, scratchCapacity, std::max<uint64_t>(b.scratchBytes, 16));
    std::memcpy(staging, jobs.data(), n * sizeof(GpuDecodeJob));
    std::memcpy(staging + jobBytes, b.coded.data(), b.coded.size() * sizeof(CodedJob));
    std::memcpy(staging + jobBytes + codedBytes, b.simple.data(),
                b.simple.size() * sizeof(uint32_t));
    AFAM_CUDA_CHECK(cudaMemcpyAsync(tables, staging, tableBytes, cudaMemcpyHostToDevice, stream));
    AFAM_CUDA_CHECK(cudaMemsetAsync(status, 0, n * sizeof(uint32_t), stream));
    const auto* base = static_cast<const unsigned char*>(tables);
    return {reinterpret_cast<const GpuDecodeJob*>(base),
            reinterpret_cast<const CodedJob*>(base + jobBytes),
            reinterpret_cast<const uint32_t*>(base + jobBytes + codedBytes)};
  }

  /// The kernels of a batch on `stream`: frames, then sums (in shared memory, then the larger
  /// jobs in global memory), and the constant and uncoded jobs.
  void launch(const Tables& t, const BatchLayout& b, const uint8_t* payloads, float* output,
              cudaStream_t stream) {
    if (!b.coded.empty()) {
      decodeFramesKernel<<<unsigned(b.coded.size()), kWarp, 0, stream>>>(t.jobs, t.coded, payloads,
                                                                         scratch, status);
      AFAM_CUDA_CHECK(cudaGetLastError());
    }
    if (b.sharedJobs > 0) {
      const size_t bytes = roundUp(b.sharedPoints * sizeof(uint32_t), 16);
      lorenzoSharedKernel<<<unsigned(b.sharedJobs), kSharedThreads, bytes, stream>>>(
          t.jobs, t.coded, payloads, scratch, output, status);
      AFAM_CUDA_CHECK(cudaGetLastError());
    }
    if (b.coded.size() > b.sharedJobs) {
      lorenzoGlobalKernel<<<unsigned(b.coded.size() - b.sharedJobs), kThreads, 0, stream>>>(
          t.jobs, t.coded + b.sharedJobs, payloads, scratch, output, status);
      AFAM_CUDA_CHECK(cudaGetLastError());
    }
    if (!b.simple.empty()) {
      simpleKernel<<<unsigned(b.simple.size()), kThreads, 0, stream>>>(t.jobs, t.simple, payloads,
                                                                       output, status);
      AFAM_CUDA_CHECK(cudaGetLastError());
    }
    if (hasInterpolants) interpolants.launch(t.jobs, payloads, output, status, stream);
  }
};

GpuBlockDecoder::GpuBlockDecoder(int device) : impl_(std::make_unique<Impl>()) {
  impl_->device = device;
  try {
    AFAM_CUDA_CHECK(cudaSetDevice(device));
    AFAM_CUDA_CHECK(cudaStreamCreateWithFlags(&impl_->own, cudaStreamNonBlocking));
    AFAM_CUDA_CHECK(cudaEventCreateWithFlags(&impl_->done, cudaEventDisableTiming));
    impl_->allowSharedMemory();
  } catch (...) {
    impl_->release();
    throw;
  }
}

GpuBlockDecoder::~GpuBlockDecoder() { impl_->release(); }

void* GpuBlockDecoder::stream() const { return impl_->own; }
size_t GpuBlockDecoder::scratchBytes() const {
  return impl_->scratchCapacity + impl_->interpolants.scratchBytes();
}

void GpuBlockDecoder::setSharedJobLimit(uint64_t controlPoints) {
  impl_->sharedLimit = std::min(controlPoints, impl_->sharedCapacity);
}

void GpuBlockDecoder::decodeAsync(const std::vector<GpuDecodeJob>& jobs, const void* payloads,
                                  float* output, void* streamArg) {
  Impl& d = *impl_;
  AFAM_CUDA_CHECK(cudaSetDevice(d.device));
  if (d.inFlight) wait();  // the staging and the scratch are the batch before's until then
  cudaStream_t stream = streamArg ? static_cast<cudaStream_t>(streamArg) : d.own;
  d.jobCount = jobs.size();
  d.result.assign(jobs.size(), code(Status::NotRun));
  if (jobs.empty()) return;
  const BatchLayout layout = layOut(jobs, d.sharedLimit);
  const Impl::Tables tables = d.upload(jobs, layout, stream);
  d.hasInterpolants = d.interpolants.upload(jobs, stream);
  d.launch(tables, layout, static_cast<const uint8_t*>(payloads), output, stream);
  AFAM_CUDA_CHECK(cudaMemcpyAsync(d.statusHost, d.status, jobs.size() * sizeof(uint32_t),
                                  cudaMemcpyDeviceToHost, stream));
  AFAM_CUDA_CHECK(cudaEventRecord(d.done, stream));
  d.inFlight = true;
}

const std::vector<uint32_t>& GpuBlockDecoder::wait() {
  Impl& d = *impl_;
  if (!d.inFlight) return d.result;
  d.inFlight = false;
  AFAM_CUDA_CHECK(cudaEventSynchronize(d.done));
  d.result.assign(d.statusHost, d.statusHost + d.jobCount);
  return d.result;
}

const std::vector<uint32_t>& GpuBlockDecoder::decode(const std::vector<GpuDecodeJob>& jobs,
                                                     const void* payloads, float* output,
                                                     void* stream) {
  decodeAsync(jobs, payloads, output, stream);
  return wait();
}

}  // namespace afam
