// SPDX-License-Identifier: BSD-3-Clause
#include "zfp_codec.hpp"

#include <chrono>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"

#ifdef AFAM_HAVE_ZFP
#include <zfp.h>
#endif

namespace afam {

#ifdef AFAM_HAVE_ZFP

namespace {

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct ZfpHandles {
  zfp_field* field = nullptr;
  zfp_field* decoded = nullptr;
  zfp_stream* stream = nullptr;
  bitstream* bits = nullptr;
  ~ZfpHandles() {
    if (bits) stream_close(bits);
    if (stream) zfp_stream_close(stream);
    if (decoded) zfp_field_free(decoded);
    if (field) zfp_field_free(field);
  }
};

}  // namespace

bool zfpAvailable() { return true; }

ZfpRoundTrip zfpRoundTrip(ZfpMode mode, double parameter, const float* in, size_t nx, size_t ny,
                          size_t nz, float* out, int threads) {
  if (!(parameter > 0))
    throw InvalidArgument("zfp: the rate or tolerance must be > 0, not " +
                          std::to_string(parameter));
  if (nx == 0 || ny == 0 || nz == 0) throw InvalidArgument("zfp: empty array");
  if (threads < 1) throw InvalidArgument("zfp: threads must be >= 1");
  ZfpRoundTrip r;
  ZfpHandles h;
  // zfp_compress only reads the field; its API takes a non-const pointer.
  h.field = zfp_field_3d(const_cast<float*>(in), zfp_type_float, nx, ny, nz);
  h.decoded = zfp_field_3d(out, zfp_type_float, nx, ny, nz);
  h.stream = zfp_stream_open(nullptr);
  if (!h.field || !h.decoded || !h.stream) throw Error("zfp: cannot allocate the stream");
  r.effectiveParameter =
      mode == ZfpMode::FixedRate
          ? zfp_stream_set_rate(h.stream, parameter, zfp_type_float, 3, zfp_false)
          : zfp_stream_set_accuracy(h.stream, parameter);
  std::vector<unsigned char> buffer(zfp_stream_maximum_size(h.stream, h.field));
  h.bits = stream_open(buffer.data(), buffer.size());
  zfp_stream_set_bit_stream(h.stream, h.bits);
  if (threads > 1 && !(zfp_stream_set_execution(h.stream, zfp_exec_omp) &&
                       zfp_stream_set_omp_threads(h.stream, uint(threads))))
    throw Error("zfp: this libzfp compresses on one thread only (no OpenMP)");
  zfp_stream_rewind(h.stream);
  auto t0 = std::chrono::steady_clock::now();
  r.bytes = zfp_compress(h.stream, h.field);
  r.compressSeconds = secondsSince(t0);
  if (r.bytes == 0) throw Error("zfp_compress failed");
  zfp_stream_set_execution(h.stream, zfp_exec_serial);
  zfp_stream_rewind(h.stream);
  t0 = std::chrono::steady_clock::now();
  if (!zfp_decompress(h.stream, h.decoded)) throw Error("zfp_decompress failed");
  r.decompressSeconds = secondsSince(t0);
  return r;
}

#else

bool zfpAvailable() { return false; }

ZfpRoundTrip zfpRoundTrip(ZfpMode, double, const float*, size_t, size_t, size_t, float*, int) {
  throw Error("built without ZFP (install libzfp-dev and configure again)");
}

#endif

}  // namespace afam
