// SPDX-License-Identifier: BSD-3-Clause
// One rank's part of a frame (sort-last rendering): the frame of the whole volume, drawn only in
// the rank's box (rank_boxes.hpp). Every ray keeps the whole volume's sample lattice and end
// weights and is marched only near the box (FrameView::clipped); the finest cells outside the box
// are culled, so a model of a coarser level that spans several boxes is drawn by each of their
// ranks within its own box only, and each sample by exactly one rank. Early ray termination and
// the skipping of culled cells work inside the box as in any frame. The ranks' premultiplied
// images, composited in visibility order (rank_images.hpp), are the image of the whole frame.
#pragma once

#include "afam/ranks/rank_boxes.hpp"
#include "afam/render/prepared_frame.hpp"

namespace afam {

/// Restricts `frame` (a bound frame of the whole volume, e.g. Renderer::prepare's) to `box`:
/// cells outside it culled, rays clipped to it; binds the frame again. An empty box leaves every
/// cell culled (a transparent image). Throws InvalidArgument for a box outside the frame's grid.
void clipFrameToBox(PreparedFrame& frame, const CellBox& box);

}  // namespace afam
