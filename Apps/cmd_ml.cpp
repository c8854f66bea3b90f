// SPDX-License-Identifier: BSD-3-Clause
// afam ml --size N OUT.raw : a float32 Marschner-Lobb volume, written slab by slab (atomic).

#include <algorithm>
#include <cstdio>
#include <vector>

#include "afam/volume/marschner_lobb.hpp"
#include "cli.hpp"
#include "commands.hpp"
#include "raw_output.hpp"

namespace afam::cli {

int runMl(int argc, char** argv) {
  Args args(argc, argv, {"size", "dims"}, {"progress"});
  const char* usage = "afam ml --size N OUT.raw   (or --dims X,Y,Z)";
  if (args.help()) {
    std::printf(
        "usage: %s\n\n"
        "Writes the Marschner-Lobb function (alpha 0.25, fM 6) sampled on N^3 points spanning\n"
        "[-1, 1]^3 as little-endian float32, x fastest, generated and written slab by slab "
        "(memory\n"
        "stays a few planes). Value range [0, 1]. The file is written to OUT.raw.tmp and "
        "renamed.\n\n"
        "  --size N        samples per axis\n"
        "  --dims X,Y,Z    anisotropic sizes instead of --size\n"
        "  --progress      draw the progress bar even when stderr is not a terminal\n",
        usage);
    return 0;
  }
  args.expectPositional(1, usage);
  std::array<int64_t, 3> dims{};
  if (args.has("dims")) {
    dims = Args::parseDims(args.str("dims"));
  } else {
    if (!args.has("size"))
      throw InvalidArgument("--size N is required; usage: " + std::string(usage));
    const long long n = args.integer("size", 0);
    if (n < 1 || n > 100000) throw InvalidArgument("--size must be in [1, 100000]");
    dims = {n, n, n};
  }
  const std::string out = args.positional()[0];
  RawOutput file(out);
  const int64_t plane = dims[0] * dims[1];
  const int64_t chunk = std::max<int64_t>(1, (int64_t(16) << 20) / std::max<int64_t>(plane, 1));
  std::vector<float> buf;
  ProgressBar bar("ml", args.has("progress"));
  MarschnerLobb ml;
  for (int64_t z = 0; z < dims[2]; z += chunk) {
    const int64_t nz = std::min(chunk, dims[2] - z);
    buf.resize(size_t(plane * nz));
    marschnerLobbSlab(ml, dims, z, nz, buf.data());
    file.append(buf.data(), buf.size() * sizeof(float));
    bar(double(z + nz) / double(dims[2]));
  }
  file.commit();
  std::printf("wrote %s: %lldx%lldx%lld float32\n", out.c_str(), (long long)dims[0],
              (long long)dims[1], (long long)dims[2]);
  return 0;
}

}  // namespace afam::cli
