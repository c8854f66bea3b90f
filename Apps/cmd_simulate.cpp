// SPDX-License-Identifier: BSD-3-Clause
// afam simulate PREFIX --dims X,Y,Z --steps N: a run of a real simulation (Gray-Scott reaction-
// diffusion, reaction_diffusion.hpp), one raw float32 file a saved step, for time-series tests
// and benchmarks.
#include <cstdio>
#include <string>

#include "afam/volume/reaction_diffusion.hpp"
#include "cli.hpp"
#include "commands.hpp"
#include "raw_output.hpp"

namespace afam::cli {

int runSimulate(int argc, char** argv) {
  Args args(argc, argv, {"dims", "steps", "every", "warmup", "seed", "seeds"}, {"quiet"});
  const char* usage =
      "afam simulate PREFIX --dims X,Y,Z --steps N [--every K] [--warmup W] [--seed S] "
      "[--seeds C]";
  if (args.help()) {
    std::printf(
        "usage: %s\n\n"
        "A real simulation's run for time-series work: Gray-Scott reaction-diffusion of two "
        "species\n"
        "on a periodic grid (explicit Euler, 7-point Laplacian), from C cubes of the second "
        "species\n"
        "placed by seed S. After W iterations (default 500), saves the second species every K\n"
        "iterations (default 10), N times, as PREFIX_0000_XxYxZ_float32.raw, PREFIX_0001_..., "
        "which\n"
        "a shell glob lists in order for `afam encode`. The same arguments give the same bytes.\n",
        usage);
    return 0;
  }
  args.expectPositional(1, usage);
  if (!args.has("dims") || !args.has("steps"))
    throw InvalidArgument("--dims and --steps are required; usage: " + std::string(usage));
  GrayScottOptions o;
  o.dims = Args::parseDims(args.str("dims"));
  o.seed = uint64_t(args.integer("seed", 1));
  o.seeds = int(args.integer("seeds", 6));
  const long long steps = args.integer("steps", 0), every = args.integer("every", 10),
                  warmup = args.integer("warmup", 500);
  if (steps < 1 || every < 1 || warmup < 0)
    throw InvalidArgument("--steps and --every must be >= 1, --warmup >= 0");
  GrayScott sim(o);
  sim.advance(int(warmup));
  const std::string dims =
      std::to_string(o.dims[0]) + "x" + std::to_string(o.dims[1]) + "x" + std::to_string(o.dims[2]);
  for (long long k = 0; k < steps; ++k) {
    if (k > 0) sim.advance(int(every));
    char index[24];
    std::snprintf(index, sizeof index, "%04lld", k);
    const std::string path = args.positional()[0] + "_" + index + "_" + dims + "_float32.raw";
    RawOutput out(path);
    out.append(sim.v().data(), sim.v().size() * sizeof(float));
    out.commit();
    if (!args.has("quiet")) std::printf("wrote %s\n", path.c_str());
  }
  return 0;
}

}  // namespace afam::cli
