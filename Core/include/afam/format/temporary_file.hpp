// SPDX-License-Identifier: BSD-3-Clause
// The temporary files of atomic writes: PATH.tmp-XXXXXX, written, then renamed onto PATH.
//
// A writer holds an exclusive flock() on its temporary file from creation until the rename. The
// kernel drops that lock when the last descriptor of the file closes, which happens when the
// writer finishes or its process dies in any way (kill -9 included). So a temporary file whose
// lock can be taken belongs to nobody alive: its writer was killed before it could clean up.
// The next writer to the same PATH removes those (and only those) files.
#pragma once

#include <string>

namespace afam {

/// Creates PATH.tmp-XXXXXX (mode 0644, close-on-exec) and locks it; returns the descriptor and
/// sets tmpPath. The lock lasts while the descriptor is open. Throws IoError.
int createLockedTemporary(const std::string& path, std::string& tmpPath);

/// Removes the files PATH.tmp-XXXXXX (X: the six letters or digits mkstemp picks) that are
/// regular files of this user and whose lock is free (their writer is dead). Files locked by a
/// live writer, in this process or another, are left alone. Returns how many were removed.
int removeStaleTemporaries(const std::string& path);

}  // namespace afam
