// SPDX-License-Identifier: BSD-3-Clause
// afam render FILE --trajectory T.dat --view I --size W,H --out IMG.png [--ground-truth-ml]
// One point of view of a recorded trajectory, rendered on the CPU from an Adaptive-FAM, FAM or DS
// file (the method follows the file), written as PNG. Prints render_ms=<x> and, with
// --ground-truth-ml, psnr=<x> ssim=<y> against the analytic Marschner-Lobb ray cast.
#include <cstdio>

#include "afam/eval/ground_truth.hpp"
#include "afam/eval/image_metrics.hpp"
#include "afam/eval/png_io.hpp"
#include "afam/render/cpu_raycaster.hpp"
#include "afam/render/renderer.hpp"
#include "afam/scene/camera.hpp"
#include "cli.hpp"
#include "commands.hpp"
#include "device_option.hpp"
#include "render_args.hpp"

using namespace afam;
using namespace afam::cli;

int runRender(int argc, char** argv) {
  std::set<std::string> values = renderValueOptions();
  values.insert({"view", "out", "gt-out", "device", "gpu-budget-mb"});
  Args args(argc, argv, values, {"ground-truth-ml", "cold", "no-culling"});
  const char* usage =
      "afam render FILE --trajectory T.dat --view I --size W,H --out IMG.png [--ground-truth-ml]";
  if (args.help()) {
    std::printf(
        "usage: %s\n\n"
        "Renders point of view I (0-based) of a trajectory file (recorded, or from `afam "
        "trajectory`;\n"
        "the authors' camera) from FILE (.afam of any mode: adaptive, inlevel and fixed\n"
        "render the B-spline micro-models, ds the raw blocks with trilinear interpolation) with\n"
        "the CPU ray caster, writes IMG.png and prints render_ms=<x> (plus caching statistics).\n\n"
        "  --trajectory T.dat     trajectory file (required)\n"
        "  --view I               point of view index (default 0)\n"
        "  --out IMG.png          output image (required)\n"
        "  --ground-truth-ml      FILE encodes `afam ml` output: also ray-cast the analytic\n"
        "                         Marschner-Lobb function and print psnr=<x> ssim=<y>\n"
        "  --gt-out GT.png        write the ground-truth image too\n%s%s",
        usage, renderOptionsHelp(), deviceOptionHelp());
    return 0;
  }
  args.expectPositional(1, usage);
  if (!args.has("trajectory"))
    throw InvalidArgument("--trajectory is required; usage: " + std::string(usage));
  if (!args.has("out")) throw InvalidArgument("--out is required; usage: " + std::string(usage));
  const auto size = parseSize(args.str("size", "256,256"));
  const RenderOptions opts = parseRenderOptions(args);
  const auto poses = loadTrajectory(args.str("trajectory"));
  const long long view = args.integer("view", 0);
  if (view < 0 || view >= (long long)poses.size())
    throw InvalidArgument("--view " + std::to_string(view) + " outside [0, " +
                          std::to_string(poses.size()) + ")");
  auto file = AfamFile::open(args.positional()[0], args.integer("step", 0));
  Renderer renderer(file, opts);
  const DeviceChoice device =
      useDevice(renderer, args.str("device", "cpu"), args.integer("gpu-budget-mb", 2048));
  const Camera camera = Camera::fromPose(poses[size_t(view)], size.first, size.second);
  FrameStats st;
  const ImageRGBA image = renderer.renderFrame(camera, st);
  printDeviceMessages(st);
  for (const std::string& r : st.damageReports) std::fprintf(stderr, "warning: %s\n", r.c_str());
  const ImageRGB8 rgb = toRGB8(image);
  writePng(args.str("out"), rgb);
  std::printf(
      "method=%s blocks=%lld bytes=%llu caching_ms=%.3f hits=%llu misses=%llu "
      "frustum_culled=%lld tf_culled=%lld\n",
      modeName(file->header().mode), (long long)st.slots, (unsigned long long)st.poolBytes,
      st.cachingMs, (unsigned long long)st.hits, (unsigned long long)st.misses,
      (long long)st.culled.frustumBlocks, (long long)st.culled.tfBlocks);
  std::printf("device=%s%s%s\n", device.used.c_str(), device.description.empty() ? "" : " ",
              device.description.c_str());
  std::printf("render_ms=%.3f\n", st.renderMs);
  if (args.has("ground-truth-ml")) {
    PreparedFrame fr;
    renderer.prepareEmpty(camera, fr);
    ImageRGBA gt;
    renderCpuWith(fr.view, MarschnerLobbSampler{}, gt, opts.threads);
    const ImageRGB8 gtRgb = toRGB8(gt);
    if (args.has("gt-out")) writePng(args.str("gt-out"), gtRgb);
    const ImageErrors e = compare(rgb, gtRgb);
    std::printf("psnr=%.3f ssim=%.4f\n", e.psnr, e.ssim);
  }
  std::fflush(stdout);
  return 0;
}
