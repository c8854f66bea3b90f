// SPDX-License-Identifier: BSD-3-Clause
// Fitted blocks as bytes (private to Core): what a process of an EncodeTeam sends the first one
// for each block it fitted, i.e. the model as the file stores it and what the level's statistics
// count. Processes of one team run the same build, so records are copied as they lie in memory.
#pragma once

#include <cstdint>
#include <vector>

#include "block_encoding.hpp"

namespace afam {

/// Appends t's record (entry, statistics, stored bytes; not its samples) to out.
void appendFittedBlock(const BlockTask& t, std::vector<uint8_t>& out);
/// Appends the blocks of a buffer of records to out, in the order they were appended. Throws
/// FormatError when the buffer is cut short.
void readFittedBlocks(const std::vector<uint8_t>& in, std::vector<BlockTask>& out);

}  // namespace afam
