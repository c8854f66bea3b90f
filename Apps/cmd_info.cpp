// SPDX-License-Identifier: BSD-3-Clause
// afam info FILE.afam
#include <algorithm>
#include <cstdio>
#include <map>

#include "afam/format/afam_file.hpp"
#include "cli.hpp"
#include "commands.hpp"

namespace afam::cli {

namespace {

/// A run's steps: their count, key interval, and per step its time, its blocks coded in time
/// (references, residuals), the payloads its deepest block decodes from and its payload bytes.
void printSteps(const AfamFile& f) {
  std::printf("steps=%lld key_interval=%d\n", (long long)f.stepCount(), f.keyInterval());
  for (int64_t s = 0; s < f.stepCount(); ++s) {
    const auto step = AfamFile::open(f.path(), s);
    int64_t references = 0, residuals = 0;
    uint64_t bytes = 0;    // the step's own payloads
    uint32_t longest = 1;  // payloads the deepest block of the step decodes from
    for (const ModelEntry& e : step->entries()) {
      references += e.reference;
      residuals += e.residual && !e.reference;
      bytes += e.reference ? 0 : e.storedSize;
      longest = std::max(longest, e.chainLength);
    }
    std::printf(
        "step=%lld time=%.9g references=%lld residuals=%lld of %zu longest_chain=%u "
        "payload_bytes=%llu\n",
        (long long)s, f.stepTimes()[size_t(s)], (long long)references, (long long)residuals,
        step->entries().size(), longest, (unsigned long long)bytes);
  }
}

}  // namespace

int runInfo(int argc, char** argv) {
  Args args(argc, argv, {}, {});
  const char* usage = "afam info FILE.afam";
  if (args.help()) {
    std::printf(
        "usage: %s\n\n"
        "Prints the header, per level the blocks, the representations (spline, samples, constant,\n"
        "interpolant; how many coded, and of those how many in the codec's integer forms), the\n"
        "bits per coded value, the NCP histogram (max NCP over the axes), the stored bytes and\n"
        "the worst RMSE, then the file size, the size the paper's\n"
        "layout would take for the same models, and the compression ratio against the raw input\n"
        "(when the file records its sample size) and against the float32 volume.\n"
        "A run of time steps (version 3) also prints steps=N, the key interval and, per step, its\n"
        "time and how many blocks refer to the step before; the rest describes step 0.\n"
        "Reads only the header and the index.\n",
        usage);
    return 0;
  }
  args.expectPositional(1, usage);
  auto f = AfamFile::open(args.positional()[0]);
  const VolumeHeader& h = f->header();
  const Partition& part = f->partition();
  std::printf("file=%s version=%u bytes=%llu\n", f->path().c_str(), f->version(),
              (unsigned long long)f->fileSize());
  if (f->version() >= 3) printSteps(*f);
  std::printf("dims=%lldx%lldx%lld scalar=%s range=[%.9g, %.9g]\n", (long long)h.dims[0],
              (long long)h.dims[1], (long long)h.dims[2], h.scalarName.c_str(), h.valueMin,
              h.valueMax);
  std::printf("origin=%g,%g,%g spacing=%g,%g,%g\n", h.origin[0], h.origin[1], h.origin[2],
              h.spacing[0], h.spacing[1], h.spacing[2]);
  std::printf("mode=%s levels=%d blocks=%d degree=%d error_bound=%g%s bound_kind=%s",
              modeName(h.mode), h.levels, h.blocksPerAxis, h.degree, h.errorBound,
              h.relativeBound ? " (relative)" : "", boundKindName(h.boundKind));
  if (h.mode == EncodingMode::Fixed) std::printf(" ncp=%d", h.fixedNcp);
  if (h.missing == MissingKind::NaN) std::printf(" missing=nan");
  if (h.missing == MissingKind::Value) std::printf(" missing=value(%.9g)", h.missingValue);
  std::printf("\n");
  uint64_t payload = 0, paper = 0;
  for (int l = 0; l < h.levels; ++l) {
    const Int3 b = part.blocksPerAxis(l);
    std::map<int, int64_t> hist;
    uint64_t bytes = 0, paperL = 0;
    double maxRmse = 0, maxErr = 0;
    int64_t complexCount = 0, kinds[5] = {0, 0, 0, 0, 0}, coded = 0, integer = 0, masked = 0,
            lanes = 0, rounded = 0;
    double codedBits = 0, codedValues = 0;
    const int64_t s = f->levelStart(l), e = s + part.blockCount(l);
    for (int64_t i = s; i < e; ++i) {
      const ModelEntry& m = f->entries()[size_t(i)];
      const int k = std::max({m.ncp[0], m.ncp[1], m.ncp[2]});
      ++hist[k];
      bytes += m.storedSize;
      ++kinds[int(m.kind)];
      masked += m.masked;
      rounded += m.roundedPoints;
      if (m.coded) {
        ++coded;
        integer += m.integerCoded;
        lanes += m.lanesCoded;
        codedBits += 8.0 * double(m.storedSize);
        codedValues += double(controlCount(m));
      }
      paperL += h.mode == EncodingMode::Downsampled ? m.size : paperModelBytes(m.ncp, m.degree);
      maxRmse = std::max(maxRmse, double(m.rmse));
      maxErr = std::max(maxErr, double(m.maxError));
      const int nmax = std::max({m.samples[0], m.samples[1], m.samples[2]});
      if (h.mode != EncodingMode::Downsampled && k > std::min(h.degree + 1, nmax)) ++complexCount;
    }
    const BlockExtent e0 = part.extent(l, {0, 0, 0});
    std::printf(
        "level %d: blocks=%dx%dx%d samples=%dx%dx%d complex=%lld bytes=%llu max_rmse=%.4g "
        "max_error=%.4g ncp:",
        l, b[0], b[1], b[2], e0.samples[0], e0.samples[1], e0.samples[2], (long long)complexCount,
        (unsigned long long)bytes, maxRmse, maxErr);
    for (const auto& kv : hist) std::printf(" %d:%lld", kv.first, (long long)kv.second);
    std::printf(
        "\n         kinds: spline=%lld samples=%lld constant=%lld interpolant=%lld coded=%lld "
        "integer_form=%lld lanes_frames=%lld bits_per_coded_value=%.3f rounded_points=%lld",
        (long long)kinds[0], (long long)kinds[1], (long long)kinds[2], (long long)kinds[3],
        (long long)coded, (long long)integer, (long long)lanes,
        codedValues > 0 ? codedBits / codedValues : 0.0, (long long)rounded);
    if (h.missing != MissingKind::None)
      std::printf(" empty=%lld masked=%lld", (long long)kinds[4], (long long)masked);
    std::printf("\n");
    payload += bytes;
    paper += paperL;
  }
  const double raw = double(h.dims[0]) * double(h.dims[1]) * double(h.dims[2]) * 4.0;
  std::printf("payload_bytes=%llu file_bytes=%llu paper_layout_bytes=%llu (file/paper=%.4f)\n",
              (unsigned long long)payload, (unsigned long long)f->fileSize(),
              (unsigned long long)paper, double(f->fileSize()) / double(paper));
  std::printf("float32_bytes=%.0f compression_ratio=%.2f", raw, raw / double(f->fileSize()));
  if (h.sourceBytesPerSample > 0)
    std::printf(" raw_bytes=%.0f ratio_raw=%.2f", raw / 4 * h.sourceBytesPerSample,
                raw / 4 * h.sourceBytesPerSample / double(f->fileSize()));
  std::printf("\n");
  return 0;
}

}  // namespace afam::cli
