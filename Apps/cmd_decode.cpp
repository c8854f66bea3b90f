// SPDX-License-Identifier: BSD-3-Clause
// afam decode FILE.afam --level K OUT.raw

#include <cstdio>

#include "afam/encode/encoder.hpp"
#include "afam/format/afam_file.hpp"
#include "afam/render/level_decode.hpp"
#include "cli.hpp"
#include "commands.hpp"
#include "raw_output.hpp"

namespace afam::cli {

int runDecode(int argc, char** argv) {
  Args args(argc, argv, {"level", "step"}, {"progress"});
  const char* usage = "afam decode FILE.afam [--level K] [--step S] OUT.raw";
  if (args.help()) {
    std::printf(
        "usage: %s\n\n"
        "Evaluates every micro-model of level K (0 = coarsest; default the finest) on its sample\n"
        "grid and writes the level's grid as little-endian float32, x fastest, blocks joined on\n"
        "their shared boundary samples. Streams one row of blocks at a time. Prints the dims.\n"
        "--step S: time step S of a run (default 0).\n",
        usage);
    return 0;
  }
  args.expectPositional(2, usage);
  auto f = AfamFile::open(args.positional()[0], args.integer("step", 0));
  const VolumeHeader& h = f->header();
  const Partition& part = f->partition();
  const int level = int(args.integer("level", h.levels - 1));
  if (level < 0 || level >= h.levels)
    throw InvalidArgument("--level " + std::to_string(level) + " outside [0, " +
                          std::to_string(h.levels - 1) + "]");
  const Int3 nb = part.blocksPerAxis(level);
  // Output grid: per axis the blocks' samples joined on shared boundaries.
  const LevelGrid grid = levelGrid(part, level);
  const Index3 od = grid.dims;
  const auto& start = grid.start;
  const std::string out = args.positional()[1];
  RawOutput file(out);
  ProgressBar bar("decode", args.has("progress"));
  std::vector<float> slab;
  for (int kz = 0; kz < nb[2]; ++kz) {
    const int nz = part.extent(level, {0, 0, kz}).samples[2];
    const int64_t z0 = start[2][size_t(kz)];
    const int64_t planes = kz + 1 < nb[2] ? nz - 1 : nz;  // the shared plane goes with the next row
    slab.resize(size_t(od[0] * od[1] * planes));
    decodeLevelBox(*f, level, {0, 0, z0}, {od[0] - 1, od[1] - 1, z0 + planes - 1}, slab.data());
    file.writeAt(slab.data(), slab.size() * sizeof(float),
                 uint64_t(z0 * od[0] * od[1]) * sizeof(float));
    bar(double(kz + 1) / double(nb[2]));
  }
  file.commit();
  bar.finish();
  std::printf("wrote %s: level %d, %lldx%lldx%lld float32\n", out.c_str(), level, (long long)od[0],
              (long long)od[1], (long long)od[2]);
  return 0;
}

}  // namespace afam::cli
