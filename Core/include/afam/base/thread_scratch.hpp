// SPDX-License-Identifier: BSD-3-Clause
// Scratch memory of the calling thread for decoding: buffers kept from one block to the next (a
// thread decoding a frame's misses allocates once, not once a block), handed back to the system
// by releaseThreadScratch() when the thread is done for now (a load thread going idle, a frame's
// loads over), and counted over all threads by threadScratchBytes(), which the cache's byte budget
// includes: what decoding holds is memory the user gave the cache, not memory beside it.
#pragma once

#include <cstddef>
#include <cstdint>

namespace afam {

/// Buffers of one thread used at the same time, one slot each.
enum class ScratchSlot {
  Frame,        ///< an entropy frame's bytes
  Words,        ///< integer residuals
  MoreWords,    ///< integers summed from them (interpolation)
  Predictions,  ///< a row's predictions
  Doubles,      ///< double residuals (then a rounded interpolant's point codes)
  Stored,       ///< a payload's stored bytes
  ChainStored,  ///< a payload of a chain in time
  Residual,     ///< a chain's decoded residual
  Samples,      ///< an interpolant's decoded samples, then its points (readRoundedCompact)
  Count
};

/// At least `bytes` bytes of the calling thread's `slot`, 64-byte aligned; its contents are kept
/// unless it grows.
void* threadScratch(ScratchSlot slot, size_t bytes);

template <typename T>
T* threadScratch(ScratchSlot slot, size_t count) {
  return static_cast<T*>(threadScratch(slot, count * sizeof(T)));
}

/// Frees the calling thread's large slots (64 KiB or more: mapped on their own, they go straight
/// back to the system); smaller ones stay, counted, so that a thread decoding small blocks frame
/// after frame does not map them again each time. A thread's slots are all freed when it ends, or
/// by releaseAllThreadScratch (a thread about to wait long, whose small slots should not count
/// against a cache's budget meanwhile).
void releaseThreadScratch();
void releaseAllThreadScratch();

/// Bytes held in scratch by every thread together.
uint64_t threadScratchBytes();

}  // namespace afam
