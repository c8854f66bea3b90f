// SPDX-License-Identifier: BSD-3-Clause
// afam trajectory OUT.dat [--kind orbit|dolly|walk] [...] : a generated camera path in the
// trajectory format that render, replay and predict read.
#include <algorithm>
#include <cstdio>

#include "afam/scene/camera.hpp"
#include "afam/scene/trajectory_gen.hpp"
#include "cli.hpp"
#include "commands.hpp"

namespace afam::cli {

namespace {

TrajectoryOptions trajectoryOptions(const Args& args) {
  TrajectoryOptions o;
  o.kind = parseTrajectoryKind(args.str("kind", "walk"));
  const long long views = args.integer("views", 400);
  if (views < 1 || views > 10000000) throw InvalidArgument("--views must be in [1, 10000000]");
  o.views = int(views);
  const long long seed = args.integer("seed", 1);
  if (seed < 0) throw InvalidArgument("--seed must be >= 0");
  o.seed = uint64_t(seed);
  o.distance = args.real("distance", o.distance);
  o.thetaDeg = args.real("theta", o.thetaDeg);
  o.phiDeg = args.real("phi", o.phiDeg);
  o.turns = args.real("turns", o.turns);
  o.fromDistance = args.real("from", o.fromDistance);
  o.toDistance = args.real("to", o.toDistance);
  o.minDistance = args.real("min-distance", o.minDistance);
  o.maxDistance = args.real("max-distance", o.maxDistance);
  return o;
}

}  // namespace

int runTrajectory(int argc, char** argv) {
  Args args(argc, argv,
            {"kind", "views", "seed", "distance", "theta", "phi", "turns", "from", "to",
             "min-distance", "max-distance"},
            {"quiet"});
  const char* usage =
      "afam trajectory OUT.dat [--kind orbit|dolly|walk] [--views N] [--seed S]\n"
      "       [--distance D] [--theta T] [--phi P] [--turns K] [--from D0] [--to D1]\n"
      "       [--min-distance A] [--max-distance B]";
  if (args.help()) {
    std::printf(
        "usage: %s\n\n"
        "Writes a generated camera path in the trajectory format that `afam render`, `replay` and\n"
        "`predict` read: 3 N little-endian float32 (N distances, N theta, N phi in degrees); the\n"
        "camera sits at distance * (sin t cos p, sin t sin p, cos t) with the volume in [-1, "
        "1]^3,\n"
        "looking at the origin. The file is written to OUT.dat.tmp and renamed.\n\n"
        "  --kind K          walk (default): a seeded exploration with the statistics of recorded\n"
        "                    human paths (distances in [A, B], smooth theta/phi steps, pauses);\n"
        "                    orbit: a circle at --distance and --theta, starting at --phi;\n"
        "                    dolly: from --from to --to along --theta, --phi (through the volume)\n"
        "  --views N         points of view (default 400)\n"
        "  --seed S          walk: random seed (default 1; the same seed gives the same path)\n"
        "  --distance D      orbit: distance of the eye from the centre (default 1.5)\n"
        "  --theta T         orbit, dolly: polar angle in degrees (default 60)\n"
        "  --phi P           orbit: first azimuth; dolly: azimuth, degrees (default 30)\n"
        "  --turns K         orbit: full turns over the path (default 1)\n"
        "  --from D0         dolly: first distance (default 2.0)\n"
        "  --to D1           dolly: last distance (default 0.25, inside the volume)\n"
        "  --min-distance A  walk: smallest distance (default 1.0)\n"
        "  --max-distance B  walk: largest distance (default 1.7)\n"
        "  --quiet           print nothing on success\n",
        usage);
    return 0;
  }
  args.expectPositional(1, usage);
  const TrajectoryOptions o = trajectoryOptions(args);
  const std::vector<Pose> poses = generateTrajectory(o);
  const std::string out = args.positional()[0];
  writeTrajectory(out, poses);
  if (args.has("quiet")) return 0;
  double dMin = poses[0].distance, dMax = poses[0].distance;
  for (const Pose& p : poses) {
    dMin = std::min(dMin, p.distance);
    dMax = std::max(dMax, p.distance);
  }
  std::printf("wrote %s: %s, %d views, distance %.4g-%.4g\n", out.c_str(),
              trajectoryKindName(o.kind), o.views, dMin, dMax);
  return 0;
}

}  // namespace afam::cli
