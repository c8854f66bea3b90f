// SPDX-License-Identifier: BSD-3-Clause
// `afam`: the command line over Core. A dispatch table of sub-commands; adding one is one line
// here (plus its Apps/cmd_*.cpp, compiled when present, see Apps/CMakeLists.txt).
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "afam/base/errors.hpp"
#include "commands.hpp"

namespace {

struct Command {
  const char* name;
  int (*run)(int, char**);
  const char* summary;
};

const Command kCommands[] = {
    {"ml", afam::cli::runMl, "write a float32 Marschner-Lobb volume: afam ml --size N OUT.raw"},
    {"mask", afam::cli::runMask,
     "a volume with holes (ball, CT field of view, land): afam mask IN OUT.raw --shape S"},
    {"encode", afam::cli::runEncode, "encode a raw volume into an .afam file"},
    {"info", afam::cli::runInfo, "levels, NCP histograms, sizes and compression of an .afam file"},
    {"verify", afam::cli::runVerify,
     "check checksums; with --against IN.raw print rmse= and max_error="},
    {"decode", afam::cli::runDecode, "decode one level to a float32 raw volume"},
    {"extract", afam::cli::runExtract, "one step of a run as a file of its own"},
    {"enlarge", afam::cli::runEnlarge,
     "a real scan made large: resampled with noise at the new resolution"},
    {"simulate", afam::cli::runSimulate,
     "a simulation's run (Gray-Scott reaction-diffusion), one raw file a step"},
    {"trajectory", afam::cli::runTrajectory,
     "write a generated camera path (orbit, dolly, exploration walk)"},
#ifdef AFAM_HAVE_CMD_CONDITION
    {"condition", runCondition, "conditioning of the fitting systems"},
#endif
#ifdef AFAM_HAVE_CMD_RENDER
    {"render", runRender, "render an .afam file to an image"},
#endif
#ifdef AFAM_HAVE_CMD_REPLAY
    {"replay", runReplay, "replay a camera trajectory"},
#endif
#ifdef AFAM_HAVE_CMD_COMPARE
    {"compare", runCompare, "psnr/ssim of one PNG against another: afam compare TEST.png REF.png"},
#endif
#ifdef AFAM_HAVE_CMD_COMPARE_CODECS
    {"compare-codecs", runCompareCodecs,
     "Adaptive-FAM against ZFP at the same RMSE on raw volumes"},
#endif
#ifdef AFAM_HAVE_CMD_PREDICT
    {"predict", runPredict, "predict the next pose along a trajectory (prefetch predictors)"},
#endif
};

void usage(std::FILE* out) {
  std::fprintf(
      out, "usage: afam <command> [options]   (afam <command> --help for details)\n\ncommands:\n");
  for (const Command& c : kCommands) std::fprintf(out, "  %-10s %s\n", c.name, c.summary);
}

/// Memory the encoding commands free stays with the process. The encoder's threads allocate and
/// free a block's worth of buffers (its fits' control points, its candidates' payloads) every
/// block, and glibc would otherwise give the freed pages back to the kernel at once (trimming a
/// thread's heap) and fault them in again for the next block. The price: an encode's peak RSS about
/// 5% higher. The other commands, and the library in its host (ParaView), keep glibc's defaults.
void keepFreedMemory() {
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, 32 << 20);  // glibc's largest: blocks' buffers come from the heaps
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    usage(stderr);
    return 2;
  }
  const std::string name = argv[1];
  if (name == "-h" || name == "--help" || name == "help") {
    usage(stdout);
    return 0;
  }
  for (const Command& c : kCommands) {
    if (name != c.name) continue;
    if (name == "encode" || name == "compare-codecs") keepFreedMemory();
    try {
      return c.run(argc - 1, argv + 1);
    } catch (const afam::Error& e) {
      std::fprintf(stderr, "afam %s: error: %s\n", c.name, e.what());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "afam %s: error: %s\n", c.name, e.what());
    } catch (...) {
      std::fprintf(stderr, "afam %s: error: unknown exception\n", c.name);
    }
    return 1;
  }
  std::fprintf(stderr, "afam: unknown command '%s' (afam --help lists them)\n", name.c_str());
  return 2;
}
