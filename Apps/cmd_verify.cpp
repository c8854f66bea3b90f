// SPDX-License-Identifier: BSD-3-Clause
// afam verify FILE.afam [--against IN.raw] [--level K]
#include <cstdio>

#include "afam/base/errors.hpp"
#include "afam/encode/encoder.hpp"
#include "afam/format/afam_file.hpp"
#include "cli.hpp"
#include "commands.hpp"
#include "level_error.hpp"
#include "source_args.hpp"

namespace afam::cli {

int runVerify(int argc, char** argv) {
  Args args(argc, argv, {"against", "dims", "type", "level", "max-rmse"}, {"progress"});
  const char* usage =
      "afam verify FILE.afam [--against IN.raw [--dims X,Y,Z] [--type T] [--level K] [--max-rmse "
      "E]]";
  if (args.help()) {
    std::printf(
        "usage: %s\n\n"
        "Reads every micro-model and checks its CRC32. With --against, also decodes the finest "
        "level\n"
        "(or --level K) on its sample grid and compares it with the raw volume at the same sample\n"
        "positions, each sample once, streaming; prints rmse=<number> and max_error=<number>.\n"
        "IN may be raw (name_XxYxZ_type.raw or --dims/--type), NRRD or MetaImage, as for encode.\n"
        "With --max-rmse E the exit status is 1 when the RMSE is above E.\n"
        "Exit status 1 on any checksum mismatch or error.\n",
        usage);
    return 0;
  }
  args.expectPositional(1, usage);
  auto f = AfamFile::open(args.positional()[0]);
  const VolumeHeader& h = f->header();
  ProgressBar bar("verify", args.has("progress"));
  std::vector<float> payload;
  const size_t n = f->entries().size();
  size_t damaged = 0;
  for (size_t i = 0; i < n; ++i) {
    payload.resize(f->entries()[i].size / 4);
    try {
      f->readPayload(int64_t(i), payload.data());
    } catch (const FormatError& e) {  // names the block; every damaged one is listed
      std::fprintf(stderr, "damaged: %s\n", e.what());
      ++damaged;
    }
    bar(0.5 * double(i + 1) / double(n));
  }
  if (damaged > 0)
    throw FormatError(args.positional()[0] + ": " + std::to_string(damaged) + " of " +
                      std::to_string(n) + " micro-models damaged (listed above)");
  std::printf("checksums ok: %zu micro-models, %llu bytes\n", n, (unsigned long long)f->fileSize());
  if (!args.has("against")) return 0;

  const InputVolume input = openInput(args.str("against"), args);
  VolumeSource* src = input.source.get();
  if (src->dims() != h.dims)
    throw InvalidArgument(args.str("against") + ": dims differ from the .afam file's");
  const int level = int(args.integer("level", h.levels - 1));
  if (level < 0 || level >= h.levels) throw InvalidArgument("--level out of range");
  const ErrorAccumulator e =
      measureLevelError(*f, *src, level, [&](double x) { bar(0.5 + 0.5 * x); });
  bar.finish();
  const double rmse = e.rmse();
  std::printf("level=%d samples=%lld rmse=%.9g max_error=%.9g\n", level, (long long)e.count, rmse,
              e.maxError);
  if (args.has("max-rmse") && !(rmse <= args.real("max-rmse", 0)))
    throw Error("rmse " + std::to_string(rmse) + " is above --max-rmse " + args.str("max-rmse"));
  return 0;
}

}  // namespace afam::cli
