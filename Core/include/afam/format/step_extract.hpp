// SPDX-License-Identifier: BSD-3-Clause
// One step of a run written as a file of its own (`afam extract`): every model of the step as a
// reader of the run decodes it, so that the new file draws and decodes exactly as the step does
// (the same floats), to hand one step to someone or to a tool that reads one volume.
#pragma once

#include <cstdint>
#include <string>

namespace afam {

struct ExtractStats {
  int64_t models = 0;
  int64_t copied = 0;    ///< stored as they are in the run (independent payloads, references)
  int64_t resolved = 0;  ///< residual chains, stored as their decoded control points (float32)
  uint64_t bytesOut = 0;
};

/// Writes step `step` of the .afam file at `run` to `out` (version 2, atomically; a version-3 file
/// of one step when the run keeps a pointwise bound or has missing samples): a model that
/// stands on one payload (an independent entry, or a reference to one) keeps its stored bytes; a
/// model decoded from a residual chain is stored as the float32 control points it decodes to (a
/// spline, or samples). Header, partition, range and bound are the run's. The payloads are
/// checked (CRC) as they are read. Throws InvalidArgument for a step the file does not have,
/// FormatError / IoError as AfamFile does; nothing is left at `out` on error.
ExtractStats extractStep(const std::string& run, int64_t step, const std::string& out);

}  // namespace afam
