// SPDX-License-Identifier: BSD-3-Clause
// Options shared by `afam render` and `afam replay` (renderer settings, image size, trajectory).
#pragma once

#include <algorithm>
#include <string>
#include <utility>

#include "afam/predict/predictor_factory.hpp"
#include "afam/render/renderer.hpp"
#include "cli.hpp"

namespace afam::cli {

inline const char* renderOptionsHelp() {
  return "  --size W,H             image size (or N for N x N; default 256,256)\n"
         "  --step K               time step K of a run of steps (default 0)\n"
         "  --cache-blocks N       RAM cache budget in micro-models (default 200, the paper's)\n"
         "  --cache-bytes B        RAM cache budget in bytes (instead of, or with, "
         "--cache-blocks)\n"
         "  --prefetch P           none | linear | appa | forecache | lstm\n"
         "  --cold                 evict the file from the OS page cache before each point of "
         "view\n"
         "  --storage-mbps R       emulate storage of R MB/s (1 MB = 1e6 B; sleeps after reads)\n"
         "  --models compact|float how the cache keeps integer-coded models: a table and a 1- or\n"
         "                         2-byte code a control point where that is smaller (default),\n"
         "                         or float32 (the same images)\n"
         "  --sample-distance D    ray sample spacing in the normalised [-1,1]^3 frame (default "
         "0.005)\n"
         "  --termination A        a ray stops once its opacity reaches A, in (0, 1] (default\n"
         "                         1 - 1/255)\n"
         "  --shading on|off       Phong shading from the model's gradient (default on)\n"
         "  --lod distance|screen  the paper's distance bands (default) or projected sample size\n"
         "  --pixel-budget P       screen policy: allowed projected sample spacing in pixels (1)\n"
         "  --no-culling           disable frustum and transfer-function culling\n"
         "  --threads N            ray-casting threads (default: all cores)\n"
         "  --load-threads N       threads reading and decoding a frame's misses (default: all "
         "cores)\n"
         "  --load-nice N          nice steps the load and prefetch threads run below the frame\n"
         "                         (0..19, default 3; 0: the same priority)\n"
         "  --miss-budget-ms M     wait at most M ms for misses; blocks still loading are drawn\n"
         "                         from a resident coarser level (default: wait for all, as\n"
         "                         the representation's still frames do; its interactive\n"
         "                         frames, a camera in motion, use 20)\n"
         "  --nan-color R,G,B,A    draw missing samples in this colour with opacity A (each in\n"
         "                         [0, 1]; default: missing samples are not drawn)\n";
}

inline const std::set<std::string>& renderValueOptions() {
  static const std::set<std::string> s = {"size",           "cache-blocks", "cache-bytes",
                                          "prefetch",       "storage-mbps", "sample-distance",
                                          "shading",        "lod",          "pixel-budget",
                                          "threads",        "trajectory",   "load-threads",
                                          "miss-budget-ms", "step",         "nan-color",
                                          "models",         "load-nice",    "termination"};
  return s;
}

inline std::pair<int, int> parseSize(const std::string& s) {
  const size_t c = s.find_first_of(",x");
  const long long w = Args::parseInt(s.substr(0, c), "--size");
  const long long h = c == std::string::npos ? w : Args::parseInt(s.substr(c + 1), "--size");
  if (w < 1 || h < 1 || w > 16384 || h > 16384)
    throw InvalidArgument("--size: width and height must be in [1, 16384]");
  return {int(w), int(h)};
}

/// --nan-color R,G,B,A into the transfer function's NaN colour and opacity.
inline void parseNanColor(const std::string& s, TransferFunction& tf) {
  double v[4];
  size_t at = 0;
  for (int k = 0; k < 4; ++k) {
    const size_t comma = s.find(',', at);
    if ((k < 3) != (comma != std::string::npos))
      throw InvalidArgument("--nan-color: give R,G,B,A (four numbers in [0, 1]), not '" + s + "'");
    v[k] = Args::parseReal(s.substr(at, comma - at), "--nan-color");
    if (!(v[k] >= 0 && v[k] <= 1))
      throw InvalidArgument("--nan-color: " + s.substr(at, comma - at) + " is outside [0, 1]");
    at = comma + 1;
  }
  tf.nanColor = {v[0], v[1], v[2]};
  tf.nanOpacity = v[3];
}

inline RenderOptions parseRenderOptions(const Args& a) {
  RenderOptions o;
  o.threads = int(a.integer("threads", 0));
  if (o.threads < 0) throw InvalidArgument("--threads must be >= 0");
  o.loadThreads = int(a.integer("load-threads", 0));
  if (o.loadThreads < 0) throw InvalidArgument("--load-threads must be >= 0");
  o.loadNice = int(a.integer("load-nice", o.loadNice));
  if (o.loadNice < 0 || o.loadNice > 19) throw InvalidArgument("--load-nice must be in 0..19");
  o.missBudgetMs = a.real("miss-budget-ms", -1);
  if (a.has("miss-budget-ms") && !(o.missBudgetMs >= 0 && o.missBudgetMs <= kMaxMissBudgetMs))
    throw InvalidArgument("--miss-budget-ms must be a number in [0, 3600000] (an hour)");
  o.sampleDistance = float(a.real("sample-distance", 0.005));
  if (!(o.sampleDistance > 0)) throw InvalidArgument("--sample-distance must be > 0");
  o.terminationOpacity = float(a.real("termination", kTerminationOpacity));
  if (!(o.terminationOpacity > 0 && o.terminationOpacity <= 1))
    throw InvalidArgument("--termination must be in (0, 1]");
  const std::string sh = a.str("shading", "on");
  if (sh != "on" && sh != "off") throw InvalidArgument("--shading must be on or off");
  o.shading = sh == "on";
  const std::string lod = a.str("lod", "distance");
  if (lod == "distance")
    o.lod.policy = LodPolicy::Distance;
  else if (lod == "screen")
    o.lod.policy = LodPolicy::Screen;
  else
    throw InvalidArgument("--lod must be distance or screen");
  o.lod.pixelBudget = a.real("pixel-budget", 1.0);
  if (!(o.lod.pixelBudget > 0)) throw InvalidArgument("--pixel-budget must be > 0");
  if (a.has("no-culling")) o.lod.frustumCulling = o.lod.tfCulling = false;
  const long long blocks = a.integer("cache-blocks", a.has("cache-bytes") ? 0 : 200);
  const long long bytes = a.integer("cache-bytes", 0);
  if (blocks < 0 || bytes < 0) throw InvalidArgument("cache budgets must be >= 0");
  o.cache = CacheBudget{uint64_t(bytes), uint64_t(blocks)};
  if (a.has("nan-color")) parseNanColor(a.str("nan-color"), o.transferFunction);
  o.prefetch = a.str("prefetch", "none");
  o.cold = a.has("cold");
  o.storageMBps = a.real("storage-mbps", 0);
  if (o.storageMBps < 0) throw InvalidArgument("--storage-mbps must be >= 0");
  const std::string models = a.str("models", "compact");
  if (models != "compact" && models != "float")
    throw InvalidArgument("--models must be compact or float, not '" + models + "'");
  o.compactModels = models == "compact";
  const auto& names = predictorNames();
  if (std::find(names.begin(), names.end(), o.prefetch) == names.end())
    throw InvalidArgument("--prefetch must be none, linear, appa, forecache or lstm, not '" +
                          o.prefetch + "'");
  return o;
}

}  // namespace afam::cli
