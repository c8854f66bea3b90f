// SPDX-License-Identifier: BSD-3-Clause
// Sub-commands of the `afam` executable. Each takes (argc, argv) with argv[0] = the command name,
// prints `--help`, and returns the process exit code; errors are thrown (main prints one line).
#pragma once

namespace afam::cli {

int runMl(int argc, char** argv);          // afam ml --size N OUT.raw
int runMask(int argc, char** argv);        // afam mask IN OUT.raw --shape ball|fov|land
int runEncode(int argc, char** argv);      // afam encode IN.raw OUT.afam [...]
int runInfo(int argc, char** argv);        // afam info FILE.afam
int runVerify(int argc, char** argv);      // afam verify FILE.afam [--against IN.raw]
int runDecode(int argc, char** argv);      // afam decode FILE.afam --level K OUT.raw
int runExtract(int argc, char** argv);     // afam extract RUN.afam --step K OUT.afam
int runEnlarge(int argc, char** argv);     // afam enlarge IN OUT.raw --dims X,Y,Z
int runSimulate(int argc, char** argv);    // afam simulate PREFIX --dims X,Y,Z --steps N
int runTrajectory(int argc, char** argv);  // afam trajectory OUT.dat [--kind orbit|dolly|walk]

class Args;
}  // namespace afam::cli

namespace afam {
struct EncoderOptions;
namespace cli {
/// afam encode with more than one input: a run of steps (Apps/cmd_encode_run.cpp).
int encodeRunCommand(const Args& args, const EncoderOptions& options);
/// afam encode --append STEP RUN.afam (Apps/cmd_encode_run.cpp).
int appendStepCommand(const Args& args, const EncoderOptions& options);
}  // namespace cli
}  // namespace afam

// Optional commands, each defined in its own Apps/cmd_*.cpp (compiled when the file exists).
int runCondition(int argc, char** argv);      // Apps/cmd_condition.cpp
int runRender(int argc, char** argv);         // Apps/cmd_render.cpp
int runReplay(int argc, char** argv);         // Apps/cmd_replay.cpp
int runPredict(int argc, char** argv);        // Apps/cmd_predict.cpp
int runCompare(int argc, char** argv);        // Apps/cmd_compare.cpp
int runCompareCodecs(int argc, char** argv);  // Apps/cmd_compare_codecs.cpp
