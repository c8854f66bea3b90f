// SPDX-License-Identifier: BSD-3-Clause
// afam verify FILE.afam [--against IN.raw] [--level K]
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/encode/encoder.hpp"
#include "afam/format/afam_file.hpp"
#include "cli.hpp"
#include "commands.hpp"
#include "level_error.hpp"
#include "source_args.hpp"

namespace afam::cli {

namespace {

/// Reads every micro-model of one step, checking its CRC; lists each damaged one on stderr and
/// returns how many there were.
size_t damagedModels(const AfamFile& f, const std::function<void(double)>& progress) {
  std::vector<float> payload;
  const size_t n = f.entries().size();
  size_t damaged = 0;
  for (size_t i = 0; i < n; ++i) {
    payload.resize(f.entries()[i].size / 4);
    try {
      f.readPayload(int64_t(i), payload.data());
    } catch (const FormatError& e) {  // names the block; every damaged one is listed
      std::fprintf(stderr, "damaged: %s\n", e.what());
      ++damaged;
    }
    progress(double(i + 1) / double(n));
  }
  return damaged;
}

/// Whether a level's error against its input keeps a pointwise bound (every sample within it);
/// an RMSE bound holds per block and is checked on the whole level only by runs (below) and
/// --max-rmse.
bool keepsPointwise(const VolumeHeader& h, const ErrorAccumulator& e) {
  return h.boundKind != BoundKind::MaxError || e.maxError <= absoluteBound(h) * (1 + 1e-6);
}

/// A run: every step's checksums and, with inputs, each step against its own, one line a step;
/// throws when a step is damaged or above the file's bound (its RMSE, or a sample's error for a
/// pointwise bound).
int verifyRun(const Args& args, const AfamFile& f, const std::vector<std::string>& inputs) {
  const VolumeHeader& h = f.header();
  const double bound = absoluteBound(h);
  const int level = int(args.integer("level", h.levels - 1));
  if (level < 0 || level >= h.levels) throw InvalidArgument("--level out of range");
  size_t broken = 0;
  for (int64_t s = 0; s < f.stepCount(); ++s) {
    const auto step = AfamFile::open(f.path(), s);
    const size_t damaged = damagedModels(*step, [](double) {});
    std::printf("step=%lld time=%.9g damaged=%zu", (long long)s, f.stepTimes()[size_t(s)], damaged);
    broken += damaged > 0;
    if (!inputs.empty()) {
      const InputVolume input = openInput(inputs[size_t(s)], args);
      if (input.source->dims() != h.dims)
        throw InvalidArgument(inputs[size_t(s)] + ": dims differ from the .afam file's");
      const ErrorAccumulator e = measureLevelError(*step, *input.source, level, [](double) {});
      std::printf(" level=%d rmse=%.9g max_error=%.9g", level, e.rmse(), e.maxError);
      if (h.missing != MissingKind::None)
        std::printf(" missing=%lld mask_mismatches=%lld", (long long)e.missing,
                    (long long)e.maskMismatches);
      broken += !(e.rmse() <= bound * (1 + 1e-6)) || !keepsPointwise(h, e) || e.maskMismatches > 0;
    }
    std::printf("\n");
  }
  if (broken > 0)
    throw Error(f.path() + ": " + std::to_string(broken) + " of " + std::to_string(f.stepCount()) +
                " steps damaged or above the bound " + std::to_string(bound));
  return 0;
}

}  // namespace

int runVerify(int argc, char** argv) {
  Args args(argc, argv, {"against", "dims", "type", "level", "max-rmse"}, {"progress"});
  const char* usage =
      "afam verify FILE.afam [--against IN.raw [S1 ...] [--dims X,Y,Z] [--type T] [--level K] "
      "[--max-rmse E]]";
  if (args.help()) {
    std::printf(
        "usage: %s\n\n"
        "Reads every micro-model and checks its CRC32. With --against, also decodes the finest "
        "level\n"
        "(or --level K) on its sample grid and compares it with the raw volume at the same sample\n"
        "positions, each sample once, streaming; prints rmse=<number> and max_error=<number>.\n"
        "Missing samples (NaN, or the file's missing value in IN) are left out of both; a sample\n"
        "missing on one side only is a mask mismatch (exit status 1).\n"
        "IN may be raw (name_XxYxZ_type.raw or --dims/--type), NRRD or MetaImage, as for encode.\n"
        "With --max-rmse E the exit status is 1 when the RMSE is above E; a file that keeps a\n"
        "pointwise bound (afam encode --max-error) exits 1 when a sample is off by more.\n"
        "Exit status 1 on any checksum mismatch or error.\n"
        "A run of steps (version 3): every step is checked and, with --against S0 S1 ... (one\n"
        "input a step, in order), compared with its own input; one line a step, step=K rmse=R\n"
        "max_error=M; exit status 1 when a step is damaged or its RMSE is above the file's "
        "bound.\n",
        usage);
    return 0;
  }
  if (args.positional().empty()) args.expectPositional(1, usage);
  auto f = AfamFile::open(args.positional()[0]);
  std::vector<std::string> inputs;  // --against S0, then S1 ... (positional after FILE)
  if (args.has("against")) inputs.push_back(args.str("against"));
  for (size_t i = 1; i < args.positional().size(); ++i) inputs.push_back(args.positional()[i]);
  if (f->stepCount() > 1 || inputs.size() > 1) {
    if (!inputs.empty() && int64_t(inputs.size()) != f->stepCount())
      throw InvalidArgument(std::to_string(inputs.size()) + " inputs for a run of " +
                            std::to_string(f->stepCount()) + " steps");
    return verifyRun(args, *f, inputs);
  }
  const VolumeHeader& h = f->header();
  ProgressBar bar("verify", args.has("progress"));
  const size_t n = f->entries().size();
  const size_t damaged = damagedModels(*f, [&](double x) { bar(0.5 * x); });
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
  std::printf("level=%d samples=%lld rmse=%.9g max_error=%.9g", level, (long long)e.count, rmse,
              e.maxError);
  if (h.missing != MissingKind::None || e.missing > 0 || e.maskMismatches > 0)
    std::printf(" missing=%lld mask_mismatches=%lld", (long long)e.missing,
                (long long)e.maskMismatches);
  std::printf("\n");
  if (e.maskMismatches > 0)
    throw Error(std::to_string(e.maskMismatches) +
                " samples are missing on one side only: the decoded mask is not the input's");
  if (args.has("max-rmse") && !(rmse <= args.real("max-rmse", 0)))
    throw Error("rmse " + std::to_string(rmse) + " is above --max-rmse " + args.str("max-rmse"));
  if (!keepsPointwise(h, e))
    throw Error("max_error " + std::to_string(e.maxError) +
                " is above the file's pointwise bound " + std::to_string(absoluteBound(h)));
  return 0;
}

}  // namespace afam::cli
