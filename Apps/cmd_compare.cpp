// SPDX-License-Identifier: BSD-3-Clause
// afam compare TEST.png REFERENCE.png : image error of one PNG against another with Core's metrics
// (image_metrics.hpp: 8-bit RGB, PSNR with peak 255, SSIM 11x11 Gaussian). Prints
// psnr=<x> ssim=<y> mse=<z>, the same numbers `afam render --ground-truth-ml` prints, so images
// made elsewhere (the ParaView plugin, ParaView's own volume mapper) are scored the same way.
#include <cstdio>

#include "afam/eval/image_metrics.hpp"
#include "afam/eval/png_io.hpp"
#include "cli.hpp"
#include "commands.hpp"

using namespace afam;
using namespace afam::cli;

int runCompare(int argc, char** argv) {
  Args args(argc, argv, {}, {});
  const char* usage = "afam compare TEST.png REFERENCE.png";
  if (args.help()) {
    std::printf(
        "usage: %s\n\n"
        "Reads two PNG files of the same size (alpha dropped) and prints psnr=<dB> ssim=<index>\n"
        "mse=<x> of TEST against REFERENCE (8-bit RGB, peak 255; identical images give psnr=99).\n"
        "`afam render ... --ground-truth-ml --gt-out GT.png` writes a reference image.\n",
        usage);
    return 0;
  }
  args.expectPositional(2, usage);
  const ImageRGB8 test = readPng(args.positional()[0]);
  const ImageRGB8 reference = readPng(args.positional()[1]);
  if (test.width != reference.width || test.height != reference.height)
    throw InvalidArgument("image sizes differ: " + std::to_string(test.width) + "x" +
                          std::to_string(test.height) + " vs " + std::to_string(reference.width) +
                          "x" + std::to_string(reference.height));
  const ImageErrors e = compare(test, reference);
  std::printf("psnr=%.3f ssim=%.4f mse=%.6g\n", e.psnr, e.ssim, e.mse);
  return 0;
}
