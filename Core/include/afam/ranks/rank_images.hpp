// SPDX-License-Identifier: BSD-3-Clause
// The ranks' images of one frame made one (sort-last compositing, what IceT does in ParaView):
// premultiplied RGBA images of the same size, one a rank (clipFrameToBox, prepared_frame.hpp),
// blended pixel by pixel.
//  * Composite blending: front-to-back "over" in visibility order (RankSplit::visibilityOrder).
//    The boxes' samples are the whole ray's, so the result is the one-box image up to rounding,
//    except where early ray termination cut the one-box ray short: a rank cannot know the
//    opacity in front of its box, so each stops at terminationOpacity of its own, and the ray's
//    light after the one-box ray's stop (at most 1 - terminationOpacity of it) is added: below
//    1/255 at the renderer's termination of 1 - 1/255 (VTK's; kTerminationOpacity), up to
//    12.75/255 at 0.95 (test_box_frames.cpp measures both). Without termination only rounding
//    differs.
//  * Maximum intensity: the per-channel maximum (order free). Equal to the one-box image when
//    the transfer function's premultiplied colour and opacity do not decrease with the value (the
//    usual ramps); otherwise the ranks would have to send their maximum values instead.
// Minimum and average projections are refused (they need values, not colours, from each rank).
#pragma once

#include <vector>

#include "afam/render/image.hpp"

namespace afam {

/// The ranks' images composited into one: `images[r]` is rank r's; `order` lists every rank
/// once, front to back. blendMode: kBlendComposite or kBlendMaximum (raycast.hpp). Throws
/// InvalidArgument for no images, images of different sizes, an order that is not a permutation
/// of the ranks, or another blend mode.
ImageRGBA compositeRankImages(const std::vector<ImageRGBA>& images, const std::vector<int>& order,
                              int blendMode);

}  // namespace afam
