// SPDX-License-Identifier: BSD-3-Clause
// Piecewise-linear colour and opacity transfer functions, sampled into the RGBA table that
// raycast.hpp interpolates, and the maximum opacity over a value interval (for culling blocks
// from the index's min/max without reading their payloads).
#pragma once

#include <array>
#include <vector>

namespace afam {

struct ColorPoint {
  double value, r, g, b;
};
struct OpacityPoint {
  double value, alpha;  ///< alpha per TransferFunction::referenceDistance of ray
};

class TransferFunction {
 public:
  /// Points may come in any order; they are sorted. Outside the points the end values hold.
  std::vector<ColorPoint> colors;
  std::vector<OpacityPoint> opacities;
  double referenceDistance = 0.01;  ///< normalised-frame length the opacities refer to
  /// Missing samples (NaN, a file's fill value): drawn in nanColor with nanOpacity (per
  /// referenceDistance, like the opacities) when nanOpacity > 0; by default not drawn at all.
  /// (VTK's vtkColorTransferFunction NanColor / NanOpacity; its default colour.)
  std::array<double, 3> nanColor{{0.5, 0.0, 0.0}};
  double nanOpacity = 0.0;
  /// A table the front end sampled from its own functions (VTK's colour transfer function in any
  /// colour space, with its above / below range colours; its opacity function): RGBA entries
  /// (interleaved, alpha per referenceDistance) spanning [sampledLo, sampledHi]. When set, table()
  /// interpolates it and the points above only name what was sampled (frame_settings.hpp checks
  /// them); empty: the points, interpolated in RGB.
  std::vector<float> sampled;
  double sampledLo = 0.0, sampledHi = 0.0;

  double opacity(double value) const;
  void color(double value, double rgb[3]) const;

  /// tableSize RGBA entries (interleaved) spanning [lo, hi]; lo == hi gives a constant table.
  std::vector<float> table(int tableSize, double lo, double hi) const;

  /// Highest opacity the renderer can produce for a value in [vmin, vmax], computed on the table
  /// (what the ray caster actually interpolates): entries floor(index(vmin)) .. ceil(index(vmax)).
  static float maxOpacity(const std::vector<float>& table, double lo, double hi, double vmin,
                          double vmax);

  /// Default for a value range: three translucent shells (isosurface-like, as in the paper's
  /// quality figure) at 20-30% (blue, faint), 45-55% (green) and 70-80% (orange, strongest) of
  /// the range, transparent everywhere else (blocks entirely outside the shells are cullable).
  static TransferFunction preset(double lo, double hi);
};

}  // namespace afam
