// SPDX-License-Identifier: BSD-3-Clause
// afam encode IN.raw|IN.nrrd|IN.nhdr|IN.mha|IN.mhd OUT.afam [options]
#include <cstdio>
#include <thread>

#include "afam/encode/encoder.hpp"
#include "afam/volume/missing_value_source.hpp"
#include "cli.hpp"
#include "commands.hpp"
#include "encode_device.hpp"
#include "source_args.hpp"

namespace afam::cli {

int runEncode(int argc, char** argv) {
  Args args(argc, argv, {"dims",        "type",      "error-bound",   "levels",       "blocks",
                         "degree",      "mode",      "ncp",           "threads",      "search",
                         "spacing",     "window",    "times",         "key-interval", "append",
                         "coded-share", "max-error", "missing-value", "entropy",      "device"},
            {"relative", "float-payloads", "isotropic-ncp", "progress", "quiet"});
  const char* usage =
      "afam encode IN.raw|IN.nrrd|IN.nhdr|IN.mha|IN.mhd [IN1 ...] OUT.afam [--dims X,Y,Z]\n"
      "       [--type int8|uint8|int16|uint16|int32|uint32|int64|uint64|float32|float64]\n"
      "       [--error-bound E | --max-error E] [--relative] [--levels L] [--blocks B] [--degree "
      "P]\n"
      "       [--mode adaptive|inlevel|fixed|ds] [--ncp K] [--threads T] [--search "
      "fast|exhaustive]\n"
      "       [--missing-value V] [--times T0,T1,...] [--key-interval K] [--coded-share S]\n"
      "       [--entropy auto|zstd|lanes] [--device auto|gpu|cpu]\n"
      "       afam encode --append STEP RUN.afam [--times T] [--threads T]";
  if (args.help()) {
    std::printf(
        "usage: %s\n\n"
        "Encodes a volume into Adaptive-FAM micro-models (paper, Algorithm 1), streaming: only "
        "the\n"
        "z-planes the current blocks need are in memory. Inputs: a raw little-endian volume (x\n"
        "fastest; dims and type default to what a name like name_64x64x93_int16.raw says), or "
        "NRRD\n"
        "(.nrrd, .nhdr) and MetaImage (.mha, .mhd), raw or gzip/zlib-compressed, whose header "
        "gives\n"
        "dims, type, spacing and origin (stored in the .afam header).\n\n"
        "Several inputs are consecutive time steps of one run (a shell glob expands sorted, as\n"
        "ParaView sorts a file series), written as one file (format version 3) coded in time: a\n"
        "block whose model at the step before still meets the bound on its new samples refers to\n"
        "it and stores nothing. Every step must have the first's grid. A relative bound is\n"
        "relative to the range of the whole run.\n"
        "  --times T0,T1,...  the steps' time values, increasing (default 0, 1, 2, ...)\n"
        "  --key-interval K   a block is stored on its own at least every K steps, so that any\n"
        "                     step decodes from one payload (default 16)\n"
        "  --coded-share S    a block that is coded (on its own or as a residual) is held to S\n"
        "                     times the bound, the rest left to the steps after, which refer to\n"
        "                     it while the data drifts by less (default %g; 1: to the bound)\n"
        "  --append STEP      add STEP to the run RUN.afam in place, as a running simulation\n"
        "                     would; a kill at any moment leaves the run with its old or new\n"
        "                     steps. --times T: its time (default the last step's + 1); the\n"
        "                     run's partition and bound apply\n\n"
        "  --error-bound E   RMSE bound per micro-block (default 1e-4)\n"
        "  --max-error E     a pointwise bound instead: every sample within E, as a reader\n"
        "                    decodes it (as SZ's absolute mode and ZFP's fixed accuracy promise);\n"
        "                    written as format version 3\n"
        "  --relative        the bound is E * (max - min) of the volume (of its valid samples)\n"
        "  --missing-value V samples equal to V are missing (a land mask, outside a scan's field\n"
        "                    of view), as NaN samples always are: the bound holds on the valid\n"
        "                    samples, missing ones are stored as a compact mask per block (and\n"
        "                    blocks with none valid as empty), decoded and drawn as NaN (nothing,\n"
        "                    or the NaN colour); a file with missing samples is format version 3;\n"
        "                    a run's steps all take it, and --append takes the run's\n"
        "  --float-payloads  store float32 splines (the paper's payloads) instead of the smallest "
        "of a\n"
        "                    constant, a coded spline and coded samples per block\n"
        "  --entropy S       entropy stage of coded payloads: auto (default: per payload a lanes\n"
        "                    frame, interleaved rANS that a GPU decodes, unless zstd's is more\n"
        "                    than 2%% smaller), zstd, or lanes (every coded payload "
        "GPU-decodable,\n"
        "                    larger on small and smooth volumes)\n"
        "  --isotropic-ncp   one NCP for all three axes (the paper's); by default blocks much "
        "smoother\n"
        "                    along some axes get fewer control points there\n"
        "  --levels L        levels of detail (default: from the dimensions, down to 2 blocks "
        "along\n"
        "                    the longest axis; level 0 is the coarsest)\n"
        "  --blocks B        blocks per axis at the finest level (default: about 64 samples a "
        "block, the paper's 16 at 1024^3)\n"
        "  --degree P        B-spline degree (default 2)\n"
        "  --mode M          adaptive (default) or inlevel (every block searched; the two encode\n"
        "                    alike), fixed (NCP = n or --ncp), ds (downsampled raw blocks with a\n"
        "                    ghost layer)\n"
        "  --ncp K           NCP per axis for --mode fixed (default n)\n"
        "  --threads T       worker threads (default: all cores)\n"
        "%s"
        "  --search S        fast (default) or exhaustive (the paper's loop over every NCP)\n"
        "  --spacing SX,SY,SZ  voxel spacing stored in the header (default 1,1,1, or the input "
        "header's)\n"
        "  --progress        draw the progress bar even when stderr is not a terminal\n"
        "  --quiet           print nothing on success\n",
        usage, EncoderOptions{}.runCodedShare, encodeDeviceHelp());
    return 0;
  }
  if (args.has("append")) args.expectPositional(1, usage);
  if (!args.has("append") && args.positional().size() < 2) args.expectPositional(2, usage);
  EncoderOptions opt;
  opt.levels = int(args.integer("levels", 0));
  opt.blocksPerAxis = int(args.integer("blocks", 0));
  opt.degree = int(args.integer("degree", 2));
  if (args.has("error-bound") && args.has("max-error"))
    throw InvalidArgument(
        "give --error-bound (an RMSE) or --max-error (a pointwise bound), not both");
  opt.boundKind = args.has("max-error") ? BoundKind::MaxError : BoundKind::Rmse;
  opt.errorBound =
      args.has("max-error") ? args.real("max-error", 0) : args.real("error-bound", 1e-4);
  opt.relativeBound = args.has("relative");
  opt.compact = !args.has("float-payloads");
  opt.perAxisNcp = !args.has("isotropic-ncp");
  opt.entropy = parseEntropyStage(args.str("entropy", "auto"));
  opt.mode = parseMode(args.str("mode", "adaptive"));
  opt.fixedNcp = int(args.integer("ncp", 0));
  if (args.has("ncp") && opt.mode != EncodingMode::Fixed)
    throw InvalidArgument("--ncp needs --mode fixed");
  opt.threads = int(args.integer("threads", 0));
  opt.fastWindow = int(args.integer("window", 3));
  opt.runCodedShare = args.real("coded-share", EncoderOptions{}.runCodedShare);
  const std::string search = args.str("search", "fast");
  if (search == "fast")
    opt.search = SearchMethod::Fast;
  else if (search == "exhaustive")
    opt.search = SearchMethod::Exhaustive;
  else
    throw InvalidArgument("--search must be fast or exhaustive, not '" + search + "'");
  if (args.has("missing-value")) {
    opt.hasMissingValue = true;
    opt.missingValue = args.real("missing-value", 0);
  }
  if (args.has("append")) return appendStepCommand(args, opt);
  if (args.positional().size() > 2) return encodeRunCommand(args, opt);
  if (args.has("times") || args.has("key-interval") || args.has("coded-share"))
    throw InvalidArgument(
        "--times, --key-interval and --coded-share need several inputs (a run of steps)");
  const InputVolume input = openInput(args.positional()[0], args);
  VolumeSource* source = input.source.get();
  std::unique_ptr<MissingValueSource> filled;
  if (opt.hasMissingValue) {
    filled = std::make_unique<MissingValueSource>(*source, opt.missingValue,
                                                  parseSampleType(input.typeName));
    source = filled.get();
  }
  const std::string device = useEncodeDevice(opt, args.str("device", "auto"));
  ProgressBar bar("encode", args.has("progress"));
  opt.progress = [&](double f) { return bar(f); };
  const EncodeStats s = encodeVolume(*source, opt, args.positional()[1]);
  bar.finish();
  if (!s.aheadFailure.empty())
    std::fprintf(stderr,
                 "afam encode: asking the GPU failed (%s); the rest was fitted on the CPU\n",
                 s.aheadFailure.c_str());
  if (filled && filled->matches() == 0)
    std::fprintf(stderr,
                 "afam encode: warning: no sample equals the missing value %s; every sample was "
                 "encoded as valid\n",
                 args.str("missing-value").c_str());
  int64_t reduced = 0;
  for (const LevelStats& ls : s.levels) reduced += ls.reducedDegree;
  if (reduced > 0)
    std::fprintf(stderr,
                 "afam encode: notice: %lld blocks have an axis of fewer than %d samples; the "
                 "degree is lowered "
                 "there (fewer --blocks or --levels give larger blocks)\n",
                 (long long)reduced, opt.degree + 1);
  if (args.has("quiet")) return 0;
  const Index3 d = source->dims();
  std::printf("encoded %s -> %s\n", args.positional()[0].c_str(), args.positional()[1].c_str());
  std::printf(
      "dims=%lldx%lldx%lld type=%s mode=%s search=%s levels=%d blocks=%d degree=%d bound=%.6g%s\n",
      (long long)d[0], (long long)d[1], (long long)d[2], input.typeName.c_str(), modeName(opt.mode),
      search.c_str(), s.levelsUsed, s.blocksPerAxisUsed, opt.degree, s.bound,
      opt.boundKind == BoundKind::MaxError
          ? (opt.relativeBound ? " (relative, pointwise)" : " (pointwise)")
          : (opt.relativeBound ? " (relative)" : ""));
  std::printf(
      "seconds=%.3f cpu_seconds=%.3f threads=%d voxels_per_s_per_thread=%.4g voxels_per_cpu_s=%.4g "
      "fits=%lld blocks=%lld asked_ahead=%lld device=\"%s\" scan_seconds=%.3f "
      "levels_seconds=%.3f\n",
      s.seconds, s.cpuSeconds, s.threads, s.voxelsPerSecondPerThread(), s.voxelsPerCpuSecond(),
      (long long)s.fits, (long long)s.blocks, (long long)s.askedAhead, device.c_str(),
      s.scanSeconds, s.fitSeconds);
  if (!s.levelSampler.empty())
    std::printf("coarse_levels_filtered_by=\"%s\" load_seconds=%.3f\n", s.levelSampler.c_str(),
                s.loadSeconds);
  std::printf(
      "bytes_in=%llu bytes_out=%llu ratio=%.2f ratio_float32=%.2f paper_layout_bytes=%llu\n",
      (unsigned long long)s.bytesIn, (unsigned long long)s.bytesOut,
      double(s.bytesIn) / double(s.bytesOut), double(s.inputVoxels) * 4.0 / double(s.bytesOut),
      (unsigned long long)s.paperBytes);
  std::printf("max_block_rmse=%.6g max_block_error=%.6g bound=%.6g value_range=[%.6g, %.6g]\n",
              s.maxRmse, s.maxError, s.bound, s.valueMin, s.valueMax);
  for (size_t l = 0; l < s.levels.size(); ++l) {
    const LevelStats& ls = s.levels[l];
    std::printf(
        "level %zu: blocks=%lld searched=%lld complex=%lld exact=%lld fits=%lld "
        "bytes=%llu "
        "max_rmse=%.6g max_error=%.6g bound=%.6g seconds=%.3f sample_seconds=%.3f "
        "fit_wait_seconds=%.3f ahead_seconds=%.3f ahead_prep_seconds=%.3f upload_seconds=%.3f "
        "residual_seconds=%.3f drain_seconds=%.3f ask_wait_seconds=%.3f ncp:",
        l, (long long)ls.blocks, (long long)ls.searched, (long long)ls.complex, (long long)ls.exact,
        (long long)ls.fits, (unsigned long long)ls.payloadBytes, ls.maxRmse, ls.maxError, s.bound,
        ls.seconds, ls.sampleSeconds, ls.fitWaitSeconds, ls.aheadSeconds, ls.aheadPrepSeconds,
        ls.uploadSeconds, ls.residualSeconds, ls.drainSeconds, ls.askWaitSeconds);
    for (size_t k = 0; k < ls.ncpHistogram.size(); ++k)
      if (ls.ncpHistogram[k]) std::printf(" %zu:%lld", k, (long long)ls.ncpHistogram[k]);
    std::printf("\n");
  }
  return 0;
}

}  // namespace afam::cli
