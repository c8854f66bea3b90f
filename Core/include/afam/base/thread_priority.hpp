// SPDX-License-Identifier: BSD-3-Clause
// Background threads (the load threads, the prefetch thread) run at a lower priority than the
// frame's thread, so that a frame waking at its miss budget's deadline gets a core at once even
// while they decode on every core: on Linux a thread's nice value is its own, and raising it
// needs no privilege (lowering it again does, so a thread lowers itself once, when it starts).
// Elsewhere the priority is left as it is.
#pragma once

namespace afam {

/// Raises the calling thread's nice value by `increment` (at most to 19; <= 0: unchanged).
/// Returns false where a thread's priority cannot be lowered (another system, a refusal).
bool lowerThisThreadPriority(int increment);

/// The calling thread's nice value (0 where threads have none of their own).
int thisThreadNice();

}  // namespace afam
