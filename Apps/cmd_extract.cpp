// SPDX-License-Identifier: BSD-3-Clause
// afam extract RUN.afam --step K OUT.afam

#include <cstdio>

#include "afam/format/step_extract.hpp"
#include "cli.hpp"
#include "commands.hpp"

namespace afam::cli {

int runExtract(int argc, char** argv) {
  Args args(argc, argv, {"step"}, {});
  const char* usage = "afam extract RUN.afam --step K OUT.afam";
  if (args.help()) {
    std::printf(
        "usage: %s\n\n"
        "Writes time step K of a run as a file of one step (version 2; version 3 when the run "
        "keeps a\n"
        "pointwise bound or has missing samples) that decodes and draws\n"
        "exactly as the step does: models standing on one payload keep their stored bytes,\n"
        "models decoded from a residual chain are stored as the float32 control points they\n"
        "decode to. The run's range and bound are kept. Prints the models copied and resolved.\n",
        usage);
    return 0;
  }
  args.expectPositional(2, usage);
  if (!args.has("step"))
    throw InvalidArgument("extract: --step K is required (" + std::string(usage) + ")");
  const int64_t step = args.integer("step", 0);
  const std::string out = args.positional()[1];
  const ExtractStats st = extractStep(args.positional()[0], step, out);
  std::printf("wrote %s: step %lld, models=%lld copied=%lld resolved=%lld bytes=%llu\n",
              out.c_str(), (long long)step, (long long)st.models, (long long)st.copied,
              (long long)st.resolved, (unsigned long long)st.bytesOut);
  return 0;
}

}  // namespace afam::cli
