// SPDX-License-Identifier: BSD-3-Clause
// afam predict T.dat --predictor none|linear|appa|forecache|lstm --out PRED.dat
// Runs a next-pose predictor over a trajectory, writes the predicted next pose for every point of
// view in the trajectory format, and prints mean_position_error=<x>.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "afam/afam_file.hpp"
#include "afam/camera.hpp"
#include "afam/lod.hpp"
#include "afam/predictors/appa.hpp"
#include "afam/predictors/forecache.hpp"
#include "afam/predictors/lstm.hpp"
#include "afam/predictors/pose_predictor.hpp"
#include "afam/predictors/prefetch_predictors.hpp"
#include "afam/transfer_function.hpp"
#include "cli.hpp"
#include "commands.hpp"

using namespace afam;

int runPredict(int argc, char** argv) {
  cli::Args args(argc, argv, {"predictor", "out", "file", "lstm-weights"}, {});
  const char* usage = "afam predict T.dat --predictor none|linear|appa|forecache|lstm --out PRED.dat "
                      "[--file F.afam] [--lstm-weights W.bin]";
  if (args.help()) {
    std::printf(
        "usage: %s\n\n"
        "For every point of view i of the trajectory T.dat, feeds poses 0..i to the predictor and\n"
        "writes its prediction of pose i+1 to PRED.dat (same format: N distances, N theta, N phi,\n"
        "float32; entry i is the prediction made at view i). Prints mean_position_error=<x>: the mean\n"
        "distance between predicted and actual next eye positions in the normalised frame over views\n"
        "0..N-2, and mean_inference_us=<t>.\n\n"
        "  --predictor P     none (stay), linear (last-pose extrapolation), appa (parent POV of the\n"
        "                    6-degree / 0.1 table), forecache (Markov + signature, phase switched),\n"
        "                    lstm (data/lstm_pose_v1.bin)\n"
        "  --file F.afam     appa: build or load F.afam.appa and print its size and build time;\n"
        "                    forecache: enables the signature model (block statistics of F)\n"
        "  --lstm-weights W  weights file for lstm (default %s)\n",
        usage, defaultLstmWeightsPath().c_str());
    return 0;
  }
  args.expectPositional(1, usage);
  if (!args.has("predictor")) throw InvalidArgument(std::string("--predictor is required; usage: ") + usage);
  if (!args.has("out")) throw InvalidArgument(std::string("--out is required; usage: ") + usage);
  const std::string name = args.str("predictor");
  const std::vector<Pose> poses = loadTrajectory(args.positional()[0]);

  std::unique_ptr<PosePredictor> predictor;
  if (args.has("file") && (name == "appa" || name == "forecache")) {
    PredictorContext ctx;
    ctx.file = AfamFile::open(args.str("file"));
    const VolumeHeader& h = ctx.file->header();
    ctx.tfLo = h.valueMin;
    ctx.tfHi = h.valueMax > h.valueMin ? h.valueMax : h.valueMin + 1.0;
    ctx.tfTable = TransferFunction::preset(ctx.tfLo, ctx.tfHi).table(1024, ctx.tfLo, ctx.tfHi);
    if (name == "appa") {
      AppaBuildReport rep;
      ctx.appaReport = &rep;
      auto p = makePrefetchPredictor("appa", ctx);
      std::printf("appa_table=%s cells=%d block_refs=%llu bytes=%llu %s_s=%.3f%s%s\n", rep.path.c_str(),
                  rep.cells, static_cast<unsigned long long>(rep.entries),
                  static_cast<unsigned long long>(rep.bytes), rep.loadedFromCache ? "load" : "build",
                  rep.seconds, rep.rebuiltBecause.empty() ? "" : " rebuilt_because=",
                  rep.rebuiltBecause.c_str());
      predictor = std::make_unique<AppaPosePredictor>(ctx.appaGrid);
    } else {
      const LodSelector selector(ctx.lod);
      ForeCacheDataSource data;
      data.visibleBlocks = makeLodVisibleFn(ctx.file, selector, 256, 256, ctx.tfTable, ctx.tfLo, ctx.tfHi);
      auto file = ctx.file;
      data.signature = [file](int64_t e) { return entrySignature(*file, e); };
      predictor = std::make_unique<ForeCachePosePredictor>(ForeCacheOptions{}, std::move(data));
    }
  } else {
    PosePredictorOptions opt;
    opt.lstmWeights = args.str("lstm-weights");
    predictor = makePosePredictor(name, opt);
  }

  std::vector<Pose> pred(poses.size());
  double err = 0, us = 0;
  int phases[3] = {0, 0, 0};
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    predictor->observe(poses[i]);
    pred[i] = predictor->predictNext();
    us += std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
    if (auto* fc = dynamic_cast<ForeCachePosePredictor*>(predictor.get())) ++phases[int(fc->phase())];
    if (i + 1 < poses.size()) err += poseDistance(pred[i], poses[i + 1]);
  }
  writeTrajectory(args.str("out"), pred);
  if (name == "forecache")
    std::printf("phases foraging=%d navigation=%d sensemaking=%d\n", phases[0], phases[1], phases[2]);
  std::printf("predictor=%s views=%zu mean_inference_us=%.2f\n", name.c_str(), poses.size(),
              poses.empty() ? 0.0 : us / double(poses.size()));
  std::printf("mean_position_error=%.6f\n", poses.size() > 1 ? err / double(poses.size() - 1) : 0.0);
  return 0;
}
