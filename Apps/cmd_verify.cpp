// SPDX-License-Identifier: BSD-3-Clause
// afam verify FILE.afam [--against IN.raw] [--level K]
#include <cmath>
#include <cstdio>

#include "afam/afam_file.hpp"
#include "afam/encoder.hpp"
#include "cli.hpp"
#include "commands.hpp"
#include "source_args.hpp"

namespace afam::cli {

int runVerify(int argc, char** argv) {
  Args args(argc, argv, {"against", "dims", "type", "level", "max-rmse"}, {"progress"});
  const char* usage = "afam verify FILE.afam [--against IN.raw [--dims X,Y,Z] [--type T] [--level K] [--max-rmse E]]";
  if (args.help()) {
    std::printf(
        "usage: %s\n\n"
        "Reads every micro-model and checks its CRC32. With --against, also decodes the finest level\n"
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
  const Partition& part = f->partition();
  ProgressBar bar("verify", args.has("progress"));
  std::vector<float> payload;
  const size_t n = f->entries().size();
  for (size_t i = 0; i < n; ++i) {
    payload.resize(f->entries()[i].size / 4);
    f->readPayload(int64_t(i), payload.data());  // throws FormatError naming the block
    bar(0.5 * double(i + 1) / double(n));
  }
  std::printf("checksums ok: %zu micro-models, %llu bytes\n", n, (unsigned long long)f->fileSize());
  if (!args.has("against")) return 0;

  const InputVolume input = openInput(args.str("against"), args);
  VolumeSource* src = input.source.get();
  if (src->dims() != h.dims)
    throw InvalidArgument(args.str("against") + ": dims differ from the .afam file's");
  const int level = int(args.integer("level", h.levels - 1));
  if (level < 0 || level >= h.levels) throw InvalidArgument("--level out of range");
  BlockRowReader reader(*src, part);
  const Int3 nb = part.blocksPerAxis(level);
  std::vector<std::vector<float>> raw;
  std::vector<float> decoded;
  double sumSq = 0, maxErr = 0;
  int64_t count = 0;
  for (int kz = 0; kz < nb[2]; ++kz) {
    reader.readRow(level, kz, false, raw);
    for (int j = 0; j < nb[1]; ++j)
      for (int i = 0; i < nb[0]; ++i) {
        const Int3 ijk{i, j, kz};
        const int64_t ei = f->entryIndex(level, ijk);
        const ModelEntry& m = f->entries()[size_t(ei)];
        payload.resize(m.size / 4);
        f->readPayload(ei, payload.data());
        decodeBlockSamples(m, payload.data(), h.mode, decoded);
        const std::vector<float>& r = raw[size_t(j) * size_t(nb[0]) + size_t(i)];
        // Count each shared boundary sample once: skip the last sample on an axis unless the block
        // is the last one along it.
        const int ex = m.samples[0] - (i + 1 < nb[0] ? 1 : 0), ey = m.samples[1] - (j + 1 < nb[1] ? 1 : 0),
                  ez = m.samples[2] - (kz + 1 < nb[2] ? 1 : 0);
        for (int z = 0; z < std::max(ez, 1); ++z)
          for (int y = 0; y < std::max(ey, 1); ++y)
            for (int x = 0; x < std::max(ex, 1); ++x) {
              const size_t k = (size_t(z) * size_t(m.samples[1]) + size_t(y)) * size_t(m.samples[0]) + size_t(x);
              const double d = double(decoded[k]) - double(r[k]);
              sumSq += d * d;
              maxErr = std::max(maxErr, std::fabs(d));
              ++count;
            }
      }
    bar(0.5 + 0.5 * double(kz + 1) / double(nb[2]));
  }
  bar.finish();
  const double rmse = std::sqrt(sumSq / double(std::max<int64_t>(count, 1)));
  std::printf("level=%d samples=%lld rmse=%.9g max_error=%.9g\n", level, (long long)count, rmse, maxErr);
  if (args.has("max-rmse") && !(rmse <= args.real("max-rmse", 0)))
    throw Error("rmse " + std::to_string(rmse) + " is above --max-rmse " + args.str("max-rmse"));
  return 0;
}

}  // namespace afam::cli
