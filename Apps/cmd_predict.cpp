// SPDX-License-Identifier: BSD-3-Clause
// afam predict T.dat --predictor none|linear|appa|forecache|lstm --out PRED.dat
// Runs a predictor (makePrefetchPredictor, the renderer's) over a trajectory, writes the predicted
// next pose for every point of view in the trajectory format, and prints mean_position_error=<x>.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "afam/format/afam_file.hpp"
#include "afam/predict/lstm.hpp"
#include "afam/predict/predictor_factory.hpp"
#include "afam/scene/camera.hpp"
#include "afam/scene/transfer_function.hpp"
#include "cli.hpp"
#include "commands.hpp"

using namespace afam;

namespace {

// The scene the data-aware predictors see: FILE, default LOD settings, the preset transfer function
// over the file's value range.
PredictorContext fileContext(const std::string& path) {
  PredictorContext ctx;
  ctx.file = AfamFile::open(path);
  const VolumeHeader& h = ctx.file->header();
  ctx.tfLo = h.valueMin;
  ctx.tfHi = h.valueMax > h.valueMin ? h.valueMax : h.valueMin + 1.0;
  ctx.tfTable = TransferFunction::preset(ctx.tfLo, ctx.tfHi).table(1024, ctx.tfLo, ctx.tfHi);
  return ctx;
}

void printAppaReport(const AppaBuildReport& rep) {
  std::printf("appa_table=%s cells=%d block_refs=%llu bytes=%llu %s_s=%.3f%s%s\n", rep.path.c_str(),
              rep.cells, static_cast<unsigned long long>(rep.entries),
              static_cast<unsigned long long>(rep.bytes), rep.loadedFromCache ? "load" : "build",
              rep.seconds,
              rep.rebuiltBecause.empty() ? "" : " rebuilt_because=", rep.rebuiltBecause.c_str());
}

}  // namespace

int runPredict(int argc, char** argv) {
  cli::Args args(argc, argv, {"predictor", "out", "file", "lstm-weights"}, {});
  const char* usage =
      "afam predict T.dat --predictor none|linear|appa|forecache|lstm --out PRED.dat "
      "[--file F.afam] [--lstm-weights W.bin]";
  if (args.help()) {
    std::printf(
        "usage: %s\n\n"
        "For every point of view i of the trajectory T.dat, gives the renderer's prefetch\n"
        "predictor the cameras of poses 0..i (the last 16, as the renderer keeps them) and\n"
        "writes its prediction of pose i+1 (pose i when it makes none) to PRED.dat (same\n"
        "format: N distances, N theta, N phi, float32; entry i is the prediction made at view i).\n"
        "Prints mean_position_error=<x>: the mean distance between predicted and actual next eye\n"
        "positions in the normalised frame over views 0..N-2, and mean_inference_us=<t>.\n\n"
        "  --predictor P     none (stay), linear (last-pose extrapolation), appa (parent POV\n"
        "                    of the 6-degree / 0.1 table), forecache (Markov + signature,\n"
        "                    phase switched),\n"
        "                    lstm (data/lstm_pose_v1.bin)\n"
        "  --file F.afam     appa: build or load F.afam.appa and print its size and build time;\n"
        "                    forecache: enables the signature model (block statistics of F)\n"
        "  --lstm-weights W  weights file for lstm (default %s)\n",
        usage, defaultLstmWeightsPath().c_str());
    return 0;
  }
  args.expectPositional(1, usage);
  if (!args.has("predictor"))
    throw InvalidArgument(std::string("--predictor is required; usage: ") + usage);
  if (!args.has("out")) throw InvalidArgument(std::string("--out is required; usage: ") + usage);
  const std::string name = args.str("predictor");
  const std::vector<Pose> poses = loadTrajectory(args.positional()[0]);

  const bool usesFile = args.has("file") && (name == "appa" || name == "forecache");
  PredictorContext ctx = usesFile ? fileContext(args.str("file")) : PredictorContext{};
  ctx.lstmWeights = args.str("lstm-weights");
  AppaBuildReport report;
  if (name == "appa" && ctx.file) ctx.appaReport = &report;
  const std::unique_ptr<Predictor> predictor = makePrefetchPredictor(name, ctx);
  if (ctx.appaReport) printAppaReport(report);

  std::vector<Pose> pred(poses.size());
  std::vector<Camera> history;
  double err = 0, us = 0;
  int phases[3] = {0, 0, 0};
  const auto* foreCache = dynamic_cast<const ForeCachePredictor*>(predictor.get());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    pred[i] = predictNextPose(*predictor, history, poses[i]);
    us += std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
    if (foreCache) ++phases[int(foreCache->phase())];
    if (i + 1 < poses.size()) err += poseDistance(pred[i], poses[i + 1]);
  }
  writeTrajectory(args.str("out"), pred);
  if (name == "forecache")
    std::printf("phases foraging=%d navigation=%d sensemaking=%d\n", phases[0], phases[1],
                phases[2]);
  std::printf("predictor=%s views=%zu mean_inference_us=%.2f\n", name.c_str(), poses.size(),
              poses.empty() ? 0.0 : us / double(poses.size()));
  std::printf("mean_position_error=%.6f\n",
              poses.size() > 1 ? err / double(poses.size() - 1) : 0.0);
  return 0;
}
