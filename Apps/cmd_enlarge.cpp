// SPDX-License-Identifier: BSD-3-Clause
// afam enlarge IN OUT_XxYxZ_type.raw --dims X,Y,Z : a real scan made large (enlarged_scan.hpp),
// written in the input's sample type, slab by slab on every core (atomic).

#include <algorithm>
#include <cstdio>
#include <thread>
#include <vector>

#include "afam/volume/enlarged_scan.hpp"
#include "afam/volume/sample_type.hpp"
#include "cli.hpp"
#include "commands.hpp"
#include "raw_output.hpp"
#include "source_args.hpp"

namespace afam::cli {

int runEnlarge(int argc, char** argv) {
  Args args(argc, argv,
            {"dims", "noise", "tissue-noise", "detail", "detail-beta", "seed", "threads"},
            {"progress"});
  const char* usage =
      "afam enlarge IN OUT.raw --dims X,Y,Z [--noise auto|S] [--tissue-noise S] [--detail D "
      "[--detail-beta B]] [--seed N] [--threads T]";
  if (args.help()) {
    std::printf(
        "usage: %s\n\n"
        "A real scan made large, for benchmarks whose blocks must cost what a real scan's cost: "
        "IN\n"
        "(any volume `afam encode` reads; small, it is held in memory) resampled to X x Y x Z "
        "samples\n"
        "spanning the same box (Catmull-Rom, linear beyond the faces), plus Gaussian noise at the "
        "new\n"
        "resolution, written in IN's sample type (rounded and clamped) as little-endian raw, x\n"
        "fastest, slab by slab on every core; name OUT name_XxYxZ_type.raw to encode it by its "
        "name.\n"
        "The same arguments give the same bytes. Written to OUT.tmp and renamed.\n\n"
        "  --dims X,Y,Z    samples per axis of the large volume (each >= 2)\n"
        "  --noise auto|S  noise standard deviation in IN's units; auto (default): IN's own, from "
        "its\n"
        "                  finest differences along x (median absolute difference / 0.954)\n"
        "  --tissue-noise S  noise standard deviation in tissue (as --detail tells it from air; "
        "default:\n"
        "                  --noise's): a scan whose air is quiet and whose tissue is noisier\n"
        "  --detail D      add detail at every scale, standard deviation D in IN's units "
        "(default 0:\n"
        "                  none): octaves of value noise, lattice spacings 2, 4, ... voxels up to "
        "a\n"
        "                  quarter of the largest axis (at most 128), so that coarse levels and "
        "camera\n"
        "                  paths cost what a real scan's do, not only the finest level; in\n"
        "                  tissue only (whole above 15%% of IN's value range, none below 5%%:\n"
        "                  air keeps its noise alone)\n"
        "  --detail-beta B octave amplitudes ~ spacing^B, 0..3 (default 0.5)\n"
        "  --seed N        noise and detail seed (default 1)\n"
        "  --threads T     threads (default: all cores)\n"
        "IN is a raw file named name_XxYxZ_type.raw, or a NRRD or MetaImage file.\n",
        usage);
    return 0;
  }
  args.expectPositional(2, usage);
  if (!args.has("dims"))
    throw InvalidArgument("--dims X,Y,Z is required; usage: " + std::string(usage));
  const Index3 target = Args::parseDims(args.str("dims"));
  const std::string in = args.positional()[0], out = args.positional()[1];
  InputVolume input =
      openInput(in, Args(1, argv, {}, {}));  // dims and type from its name or header
  const SampleType type = parseSampleType(input.typeName);
  const Index3 dims = input.source->dims();
  std::vector<float> samples(size_t(dims[0] * dims[1] * dims[2]));
  input.source->readSlab(0, dims[2], samples.data());
  const std::string noiseArg = args.has("noise") ? args.str("noise") : "auto";
  const double sigma =
      noiseArg == "auto" ? estimateScanNoise(samples, dims) : args.real("noise", 0);
  double lo, hi;
  sampleTypeRange(type, lo, hi);
  const uint64_t seed = uint64_t(args.integer("seed", 1));
  const double detail = args.real("detail", 0), beta = args.real("detail-beta", 0.5);
  const double tissueSigma = args.has("tissue-noise") ? args.real("tissue-noise", 0) : sigma;
  EnlargedScanSource check(std::vector<float>(1, 0.f), {1, 1, 1}, target, 0, seed, lo, hi);
  check.setDetail(detail, beta);  // bad values refused before OUT.tmp is created
  check.setTissueNoise(tissueSigma);
  const int threads = int(args.integer("threads", 0)) > 0
                          ? int(args.integer("threads", 0))
                          : int(std::max(1u, std::thread::hardware_concurrency()));
  const int64_t plane = target[0] * target[1];
  const int64_t chunk = std::max<int64_t>(1, (int64_t(8) << 20) / std::max<int64_t>(plane, 1));
  RawOutput file(out);
  {
    // Each thread owns a source (its own cache of resampled planes) and one slab of a round.
    std::vector<EnlargedScanSource> sources;
    for (int t = 0; t < threads; ++t) {
      sources.emplace_back(samples, dims, target, sigma, seed, lo, hi);
      sources.back().setDetail(detail, beta);
      sources.back().setTissueNoise(tissueSigma);
    }
    const size_t slabBytes = size_t(plane * chunk) * size_t(sampleTypeSize(type));
    std::vector<std::vector<float>> values(static_cast<size_t>(threads));
    std::vector<std::vector<unsigned char>> bytes(static_cast<size_t>(threads),
                                                  std::vector<unsigned char>(slabBytes));
    ProgressBar bar("enlarge", args.has("progress"));
    for (int64_t z = 0; z < target[2]; z += chunk * threads) {
      std::vector<std::thread> pool;
      for (int t = 0; t < threads; ++t)
        pool.emplace_back([&, t] {
          const int64_t z0 = z + t * chunk, nz = std::min(chunk, target[2] - z0);
          if (nz <= 0) return;
          values[size_t(t)].resize(size_t(plane * nz));
          sources[size_t(t)].readSlab(z0, nz, values[size_t(t)].data());
          floatToSamples(type, values[size_t(t)].data(), uint64_t(plane * nz),
                         bytes[size_t(t)].data());
        });
      for (std::thread& th : pool) th.join();
      for (int t = 0; t < threads; ++t) {
        const int64_t z0 = z + t * chunk, nz = std::min(chunk, target[2] - z0);
        if (nz > 0)
          file.append(bytes[size_t(t)].data(), size_t(plane * nz) * size_t(sampleTypeSize(type)));
      }
      bar(double(std::min(target[2], z + chunk * threads)) / double(target[2]));
    }
  }
  file.commit();
  std::printf("wrote %s: %lldx%lldx%lld %s from %s (%lldx%lldx%lld), noise sigma %.4g", out.c_str(),
              (long long)target[0], (long long)target[1], (long long)target[2],
              sampleTypeName(type), in.c_str(), (long long)dims[0], (long long)dims[1],
              (long long)dims[2], sigma);
  if (tissueSigma != sigma) std::printf(", in tissue %.4g", tissueSigma);
  if (detail > 0) std::printf(", detail sd %.4g beta %.4g", detail, beta);
  std::printf("\n");
  return 0;
}

}  // namespace afam::cli
