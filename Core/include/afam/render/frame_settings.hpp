// SPDX-License-Identifier: BSD-3-Clause
// The settings that may change with every frame (Renderer::setFrameSettings), and the checks a
// front end runs on what a person typed before handing it over: each unusable setting is named
// with its value, and the last good value is kept, so an editor never crashes or goes blank on a
// half-edited transfer function or a zero sample distance.
#pragma once

#include <string>
#include <vector>

#include "afam/render/raycast.hpp"
#include "afam/scene/lod.hpp"
#include "afam/scene/transfer_function.hpp"

namespace afam {

/// What may change from one frame to the next while the cache, the prefetcher's state and a GPU
/// model pool stay as they are.
struct FrameSettings {
  float sampleDistance = 0.005f;  ///< normalised units ([-1, 1]^3 volume), > 0
  bool shading = true;
  /// Each pixel's samples shifted by a stable fraction of a step (FrameView::jitter): no banding.
  bool jitter = true;
  LodOptions lod;
  int tfTableSize = 1024;
  /// false: TransferFunction::preset over the file's range, with transferFunction's NaN colour and
  /// opacity (missing samples drawn or not, whichever table draws the rest).
  bool hasTransferFunction = false;
  TransferFunction transferFunction;
  float ambient = 0.3f, diffuse = 0.6f, specular = 0.3f, specularPower = 20.f;
  /// BlendMode (raycast.hpp): composite (0) or maximum / minimum / average intensity projection
  /// (average: VTK's opaque grey level of the opacity-weighted mean value). Projections use the
  /// table's own opacity, not corrected for the sample distance. No projection culls blocks by the
  /// transfer function (a block the table makes transparent can still hold a ray's largest or
  /// smallest value, and counts in the mean).
  int blendMode = 0;
  /// A composited ray stops once its opacity reaches this (early ray termination), in (0, 1];
  /// 1: never before it leaves the volume. kTerminationOpacity (raycast.hpp) says why its value.
  float terminationOpacity = kTerminationOpacity;
  /// How long a frame waits for its misses, which the renderer's load threads read and decode all
  /// at once. < 0 (default): until every selected block is resident (the exact frame). >= 0: at
  /// most this many milliseconds; a block still loading is drawn from its nearest resident
  /// coarser level and refined in the next frames (FrameStats::standInBlocks). A block with no
  /// resident coarser level is always waited for. At most kMaxMissBudgetMs; NaN is refused.
  double missBudgetMs = -1;
};

/// The largest miss budget a frame takes (an hour): a larger one is a mistake (seconds for
/// milliseconds, a byte count), not a frame's wait, and its deadline would not fit the clock.
constexpr double kMaxMissBudgetMs = 3.6e6;

/// Why `tf` cannot be drawn, in words, or empty when it can: no colour or no opacity point, a
/// point whose value, colour or opacity is not finite, an opacity outside [0, 1], a reference
/// distance that is not a finite number > 0.
std::string transferFunctionProblem(const TransferFunction& tf);

/// The first reason `s` cannot be used (sample distance, blend mode, table size, pixel budget,
/// transfer function when hasTransferFunction), or empty.
std::string frameSettingsProblem(const FrameSettings& s);

/// What to draw when a front end asks for `wanted` and `kept` are the last settings that worked:
/// every unusable setting of `wanted` is replaced by kept's, and `warnings` gets one sentence for
/// each, naming the setting, the value asked for and the value kept. The result is always usable
/// when `kept` is.
FrameSettings acceptFrameSettings(const FrameSettings& wanted, const FrameSettings& kept,
                                  std::vector<std::string>& warnings);

}  // namespace afam
