// SPDX-License-Identifier: BSD-3-Clause
// Whether the ranks that draw one volume together opened one file. Each rank opens the path it
// was given on its own node; a node may hold another version of the file, or none, and the ranks'
// boxes (rank_boxes.hpp) then come from different splits and their images do not fit together.
// Each rank computes the fingerprint of what it opened (0: it could not open it), the ranks
// exchange them, and all of them read the same verdict.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "afam/format/afam_file.hpp"

namespace afam {

/// A fingerprint of a file's contents: its size, the volume's dimensions, the time step opened
/// and every index entry's place and checksum (CRC-32 of them, never 0). Equal on two nodes for
/// the same file; different, but for a CRC collision, for another encode.
uint64_t contentFingerprint(const AfamFile& file);

/// Empty when every rank opened the same file (every fingerprint equal and not 0); otherwise one
/// sentence naming `path` and the ranks that could not open it (fingerprint 0) or opened another
/// file than rank 0's (or, when rank 0 opened none, than the first rank that did).
std::string ranksFileDisagreement(const std::vector<uint64_t>& fingerprints,
                                  const std::string& path);

}  // namespace afam
