// SPDX-License-Identifier: BSD-3-Clause
// afam encode IN0 IN1 ... OUT.afam: the inputs as consecutive time steps of one run, coded in
// time (encode_run.hpp), written as format version 3.
#include <cstdio>
#include <limits>
#include <memory>
#include <sstream>

#include "afam/encode/encode_run.hpp"
#include "afam/volume/missing_value_source.hpp"
#include "cli.hpp"
#include "commands.hpp"
#include "source_args.hpp"

namespace afam::cli {

namespace {

/// "T0,T1,..." as numbers.
std::vector<double> parseTimes(const std::string& s) {
  std::vector<double> times;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, ',');) {
    try {
      size_t pos = 0;
      times.push_back(std::stod(item, &pos));
      if (pos != item.size()) throw 0;
    } catch (...) {
      throw InvalidArgument("--times: '" + item + "' is not a number");
    }
  }
  return times;
}

}  // namespace

int encodeRunCommand(const Args& args, const EncoderOptions& opt) {
  const std::vector<std::string>& pos = args.positional();
  const std::string out = pos.back();
  std::vector<InputVolume> inputs;
  std::vector<std::unique_ptr<MissingValueSource>> filled;  // --missing-value: per step
  std::vector<VolumeSource*> steps;
  for (size_t k = 0; k + 1 < pos.size(); ++k) {
    inputs.push_back(openInput(pos[k], args));
    steps.push_back(inputs.back().source.get());
    if (inputs.back().typeName != inputs.front().typeName)
      throw InvalidArgument("encode: step " + std::to_string(k) + " (" + pos[k] +
                            "): sample type " + inputs.back().typeName +
                            " differs from the first step's " + inputs.front().typeName);
    if (opt.hasMissingValue) {
      filled.push_back(std::make_unique<MissingValueSource>(
          *steps.back(), opt.missingValue, parseSampleType(inputs.back().typeName)));
      steps.back() = filled.back().get();
    }
  }
  RunOptions run;
  if (args.has("times")) run.times = parseTimes(args.str("times"));
  run.keyInterval = int(args.integer("key-interval", 16));
  const RunStats s = encodeRun(steps, opt, run, out);
  int64_t matches = 0;
  for (const auto& f : filled) matches += f->matches();
  if (opt.hasMissingValue && matches == 0)
    std::fprintf(stderr,
                 "afam encode: warning: no sample equals the missing value %s; every sample was "
                 "encoded as valid\n",
                 args.str("missing-value").c_str());
  if (args.has("quiet")) return 0;
  uint64_t bytesIn = 0, payload = 0;
  std::printf("encoded %zu steps -> %s\n", steps.size(), out.c_str());
  for (size_t k = 0; k < s.steps.size(); ++k) {
    const EncodeStats& st = s.steps[k];
    bytesIn += st.bytesIn;
    payload += st.payloadBytes;
    std::printf(
        "step=%zu time=%.9g input=%s blocks=%lld references=%lld residuals=%lld "
        "decoded_before=%lld payload_bytes=%llu max_block_rmse=%.6g seconds=%.3f\n",
        k, run.times.empty() ? double(k) : run.times[k], pos[k].c_str(), (long long)st.blocks,
        (long long)s.references[k], (long long)s.residuals[k], (long long)s.decodedBefore[k],
        (unsigned long long)st.payloadBytes, st.maxRmse, st.seconds);
  }
  std::printf(
      "steps=%zu key_interval=%d bound=%.6g%s value_range=[%.6g, %.6g] seconds=%.3f "
      "range_seconds=%.3f trial_seconds=%.3f headroom_blocks=%lld first_step_taken=%lld\n"
      "bytes_in=%llu bytes_out=%llu ratio=%.2f payload_bytes=%llu\n",
      steps.size(), run.keyInterval, s.bound, opt.relativeBound ? " (relative to the run)" : "",
      s.valueMin, s.valueMax, s.seconds, s.rangeSeconds, s.trialSeconds,
      (long long)s.headroomBlocks, (long long)s.firstStepTaken, (unsigned long long)bytesIn,
      (unsigned long long)s.bytesOut, double(bytesIn) / double(s.bytesOut),
      (unsigned long long)payload);
  return 0;
}

int appendStepCommand(const Args& args, const EncoderOptions& opt) {
  const std::string run = args.positional()[0];
  const InputVolume input = openInput(args.str("append"), args);
  // The run's fill value marks the step's missing samples as it did the run's.
  const VolumeHeader h = AfamFile::open(run)->header();
  if (opt.hasMissingValue &&
      !(h.missing == MissingKind::Value && h.missingValue == opt.missingValue))
    throw InvalidArgument("--missing-value " + args.str("missing-value") + ": the run " +
                          (h.missing == MissingKind::Value
                               ? "has the missing value " + std::to_string(h.missingValue)
                               : std::string("has no missing value")));
  std::unique_ptr<MissingValueSource> filled;
  VolumeSource* source = input.source.get();
  if (h.missing == MissingKind::Value) {
    filled = std::make_unique<MissingValueSource>(*source, h.missingValue);
    source = filled.get();
  }
  double time = std::numeric_limits<double>::quiet_NaN();
  if (args.has("times")) {
    const std::vector<double> times = parseTimes(args.str("times"));
    if (times.size() != 1) throw InvalidArgument("--times: one time value for the appended step");
    time = times[0];
  }
  if (args.has("key-interval"))
    throw InvalidArgument("--key-interval is the run's: it cannot change when appending");
  const RunStats s = appendStep(*source, time, opt, run);
  if (args.has("quiet")) return 0;
  const EncodeStats& st = s.steps[0];
  std::printf(
      "appended %s -> %s: blocks=%lld references=%lld residuals=%lld payload_bytes=%llu "
      "max_block_rmse=%.6g bound=%.6g bytes_out=%llu seconds=%.3f\n",
      args.str("append").c_str(), run.c_str(), (long long)st.blocks, (long long)s.references[0],
      (long long)s.residuals[0], (unsigned long long)st.payloadBytes, st.maxRmse, s.bound,
      (unsigned long long)s.bytesOut, s.seconds);
  return 0;
}

}  // namespace afam::cli
