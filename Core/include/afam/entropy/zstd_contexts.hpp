// SPDX-License-Identifier: BSD-3-Clause
// The calling thread's zstd contexts, kept from one frame to the next. Their large memory lies on
// huge pages (huge_pages.hpp): a compression context at a high level holds tables of megabytes
// (8 MB for a frame of 300 KB at level 15) that zstd clears on first use, and on ordinary pages
// that first use was a quarter of the page faults of encoding a one-block volume.
#pragma once

#include <zstd.h>

namespace afam {

/// The calling thread's compression context; std::bad_alloc where none can be made.
ZSTD_CCtx* threadCCtx();
/// The calling thread's decompression context; std::bad_alloc where none can be made.
ZSTD_DCtx* threadDCtx();

}  // namespace afam
