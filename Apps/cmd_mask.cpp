// SPDX-License-Identifier: BSD-3-Clause
// afam mask IN OUT.raw --shape ball|fov|land [--fill V] [--nearest FILLED.raw] : a volume with
// holes (test and benchmark data for missing samples), and the same volume with its holes filled by
// hand.

#include <cstdio>
#include <limits>
#include <vector>

#include "afam/volume/masked_volumes.hpp"
#include "cli.hpp"
#include "commands.hpp"
#include "raw_output.hpp"
#include "source_args.hpp"

namespace afam::cli {

namespace {

void writeFloats(const std::string& path, const std::vector<float>& v) {
  RawOutput out(path);
  out.append(v.data(), v.size() * sizeof(float));
  out.commit();
}

}  // namespace

int runMask(int argc, char** argv) {
  Args args(argc, argv, {"dims", "type", "shape", "fill", "seed", "nearest", "spacing"}, {});
  const char* usage =
      "afam mask IN OUT.raw --shape ball|fov|land [--fill V] [--seed S] [--nearest FILLED.raw]";
  if (args.help()) {
    std::printf(
        "usage: %s\n\n"
        "Writes IN (raw, NRRD or MetaImage, as for encode) as float32 with some samples missing:\n"
        "  ball   a ball at the centre, radius a quarter of the shortest side\n"
        "  fov    outside the cylinder along z inscribed in the xy-square (a CT's field of view)\n"
        "  land   generated continents (missing at every depth) and a sea floor rising towards\n"
        "         them (z = 0 the deepest plane), as ocean models mark land; --seed S (default 1)\n"
        "Missing samples are NaN, or V with --fill V (encode them with --missing-value V).\n"
        "--nearest FILLED.raw also writes the volume with every missing sample set to the value\n"
        "of the nearest valid one (in steps between face neighbours): what users do by hand when\n"
        "a compressor cannot take holes.\n",
        usage);
    return 0;
  }
  args.expectPositional(2, usage);
  const InputVolume input = openInput(args.positional()[0], args);
  VolumeSource& src = *input.source;
  const Index3 d = src.dims();
  const VolumeMask mask(parseMaskShape(args.str("shape", "ball")), d,
                        uint64_t(args.integer("seed", 1)));
  const float fill =
      args.has("fill") ? float(args.real("fill", 0)) : std::numeric_limits<float>::quiet_NaN();
  MaskedSource masked(src, mask);
  std::vector<float> v(size_t(d[0] * d[1] * d[2]));
  masked.readSlab(0, d[2], v.data());
  int64_t missing = 0;
  for (float x : v) missing += x != x;
  if (args.has("nearest")) {
    std::vector<float> filled = v;
    fillNearestValid(filled, d);
    writeFloats(args.str("nearest"), filled);
  }
  if (args.has("fill"))
    for (float& x : v)
      if (x != x) x = fill;
  writeFloats(args.positional()[1], v);
  std::printf("missing=%lld of %lld samples (%.2f%%)\n", (long long)missing, (long long)v.size(),
              100.0 * double(missing) / double(v.size()));
  return 0;
}

}  // namespace afam::cli
